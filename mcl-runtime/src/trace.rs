//! Traces: one JSON object per line (JSONL), and the live log.
//!
//! A line is a [`Record`]: `t` (seconds from the start of the mission),
//! `mission` when the mission is named (or when the file holds several
//! missions: then on every record, `"*"` on the `coord_summary` that
//! concerns them all), then `kind` and the fields of that kind
//! ([`RecordKind`], one variant per kind: `action`, `event`, `fire`,
//! `unexpected_event`, `stale_event`, `timer`, `perception`, `warning`,
//! `link`, `outcome`, `coord_send`, `coord_receive`, `coord_reject`,
//! `coord_summary`, `pose`, `operator`). docs/scenarios.md (*Traces*) lists every kind
//! with its fields and their types. Kinds this version does not know (the
//! planner's) are read as [`RecordKind::Other`] and ignored.
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
use serde_json::Value;

use crate::player::Output;

/// One line of a trace: when, for which mission, and what happened
/// ([`RecordKind`], whose fields follow `t`, `mission` and `kind` on the
/// line).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Seconds from the start of the mission.
    pub t: f64,
    /// The mission's name (`"*"`: every mission of a coordinated run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mission: Option<String>,
    /// What happened: the `kind` field and the fields of that kind.
    #[serde(flatten)]
    pub kind: RecordKind,
}

/// What a trace record says, tagged by its `kind` (the table in the
/// module's documentation and in docs/scenarios.md). Fields are written in
/// the order declared here.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RecordKind {
    /// An action sent to the vehicle.
    Action {
        /// Its sequence number.
        seq: u64,
        /// The action's name.
        action: String,
        /// Its primitive.
        primitive: String,
        /// Its command (`enable`, `disable`, ...).
        command: String,
        /// Its parameters, in the order the action declares them.
        params: crate::params::Params,
        /// The call that sent it.
        #[serde(flatten)]
        call: Call,
        /// Produced while the link to the AAC was down: sent once it is up.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        queued: bool,
    },
    /// An event from the vehicle fired a transition.
    Event {
        /// The event's name.
        event: String,
        /// The transition it fired.
        transition: String,
        /// The task of that transition and the call it answers.
        #[serde(flatten)]
        call: Call,
        /// The activation it named (the `seq` of the action that started
        /// the primitive run that raised it), when the AAC named one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        activation: Option<u64>,
        /// Whether it is one of its task's ok or fail events (`none`: neither).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ends: Option<Ends>,
    },
    /// A transition fired.
    Fire {
        /// Its id.
        transition: String,
        /// Its task and call; `src`: where the handler it starts is written.
        #[serde(flatten)]
        call: Call,
        /// `timeout` (a task's time-out), `catch` or `condition` (a handler).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ends: Option<Ends>,
    },
    /// An event that no transition waited for.
    UnexpectedEvent {
        /// The event's name.
        event: String,
        /// Why it was not expected.
        reason: String,
    },
    /// An answer of a primitive run disabled since (ignored).
    StaleEvent {
        /// The event's name.
        event: String,
        /// Why it is stale.
        reason: String,
        /// The activation it named.
        activation: u64,
    },
    /// A timer of a positive delay started.
    Timer {
        /// The timed transition.
        transition: String,
        /// Its task.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        task: Option<String>,
        /// When it fires (mission seconds).
        deadline: f64,
    },
    /// A perception from the vehicle.
    Perception {
        /// Its name.
        name: String,
        /// Its value.
        value: Value,
    },
    /// A warning (a scenario's missing answer, a delay without a value...).
    Warning {
        /// The warning.
        message: String,
    },
    /// What happened to the link to the AAC (connection attempts, errors
    /// the AAC reports, malformed messages, gaps in event numbers), or a
    /// resumed run.
    Link {
        /// The notice.
        message: String,
    },
    /// How the mission ended.
    Outcome {
        /// `ok`, `fail`, `stuck`, `time_limit` (`aborted` for a planned step
        /// the planner stopped).
        result: String,
        /// Why, when it did not end by itself.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reason: Option<String>,
        /// How it got there when it left its nominal path: the last handler
        /// it went through (`the catch at FILE:LINE`, `the condition of the
        /// monitor at FILE:LINE`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        via: Option<String>,
    },
    /// A coordination message sent.
    CoordSend {
        /// Its number on its link.
        seq: u64,
        /// The sender's transition (just fired).
        transition: String,
        /// The mission it is sent to.
        to: String,
    },
    /// A coordination message received.
    CoordReceive {
        /// Its number on its link.
        seq: u64,
        /// The event it becomes (`mission/transition`).
        event: String,
        /// The sender's transition.
        transition: String,
        /// The sending mission.
        from: String,
    },
    /// A coordination line or connection the transport refused.
    CoordReject {
        /// Why.
        message: String,
    },
    /// The last record of a coordinated run (`mission: "*"`).
    CoordSummary {
        /// The mutex protocol's message counts (`grants`, `requests`,
        /// `returns`), when it sent any.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        value: Option<Value>,
        /// The result of the whole run (the worst of the missions').
        result: String,
        /// Coordination messages sent.
        messages: u64,
    },
    /// Where a simulated vehicle is.
    Pose {
        /// East, metres.
        x: f64,
        /// North, metres.
        y: f64,
        /// Depth, metres (≥ 0).
        z: f64,
        /// Heading, radians (0 towards +x, counter-clockwise).
        yaw: f64,
    },
    /// A frame put on a modelled acoustic link (`--link`, docs/acoustic.md;
    /// `mission` is the sender).
    LinkSend {
        /// The receiving mission.
        to: String,
        /// Its number on the link (of the message it carries or acknowledges).
        seq: u64,
        /// The message's transition, or `ack`.
        what: String,
        /// Bytes on the wire (the compact encoding).
        bytes: u64,
        /// Bytes of the same message as JSON (0 for an acknowledgement).
        json_bytes: u64,
        /// 1 for the first transmission, 2 for the first retransmission...
        attempt: u32,
    },
    /// A frame the link lost (`mission` is the sender).
    LinkLost {
        /// The mission it was for.
        to: String,
        /// Its number on the link.
        seq: u64,
        /// The message's transition, or `ack`.
        what: String,
        /// `loss` (drawn) or `range` (the vehicles were too far apart).
        reason: String,
    },
    /// A frame that reached its receiver (`mission` is the receiver).
    LinkDeliver {
        /// The sending mission.
        from: String,
        /// Its number on the link.
        seq: u64,
        /// The message's transition, or `ack`.
        what: String,
        /// `new` (handed to the vehicle), `repeat` (already had it),
        /// `early` (kept until the frames before it arrive), `ack`.
        status: String,
    },
    /// An operator's command (`mcl run --operator-token`, docs/monitor.md),
    /// taken by the real-time driver: `command` (`pause`, `resume`,
    /// `abort`, `answer`) and, for `answer`, the `event` delivered.
    Operator {
        /// The command and its fields.
        #[serde(flatten)]
        command: crate::operator::Command,
    },
    /// A record of a kind this version does not know (the planner's `plan`,
    /// `step`... in a `mcl plan --run` trace): read, ignored by every
    /// reader.
    #[serde(other)]
    Other,
}

/// The call a record concerns: `task`, `call_site`, `label`, `src` on the line.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Call {
    /// The task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<String>,
    /// The call site (numbered by the compiler).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub call_site: Option<u32>,
    /// The call's label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// `file:line` of the call (of a handler, on a `fire`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub src: Option<String>,
}

/// What an event or a firing ends, from the compiled net (never from names).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ends {
    /// One of its task's ok events (the net's `task_events`).
    Ok,
    /// One of its task's fail events.
    Fail,
    /// An event that is neither (progress, condition).
    #[serde(rename = "none")]
    Neither,
    /// A task's timed transition fired (a time-out).
    Timeout,
    /// The transition that starts a catch fired.
    Catch,
    /// The transition that ends a monitor on its condition fired.
    Condition,
}

impl Record {
    /// A record of `kind` at time `t` (rounded to the microsecond), without
    /// a mission.
    pub fn new(t: f64, kind: RecordKind) -> Self {
        Record { t: round_time(t), mission: None, kind }
    }

    /// A `warning` record.
    pub fn warning(t: f64, message: String) -> Self {
        Record::new(t, RecordKind::Warning { message })
    }

    /// A `link` record.
    pub fn link(t: f64, message: String) -> Self {
        Record::new(t, RecordKind::Link { message })
    }

    /// An `outcome` record.
    pub fn outcome(t: f64, result: &str, reason: Option<String>) -> Self {
        Record::new(t, RecordKind::Outcome { result: result.to_string(), reason, via: None })
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
    fn ends(&self, task: Option<&str>, event: &str) -> Option<Ends> {
        let e = self.outcomes.get(task?)?;
        Some(if e.ok.iter().any(|x| x == event) {
            Ends::Ok
        } else if e.fail.iter().any(|x| x == event) {
            Ends::Fail
        } else {
            Ends::Neither
        })
    }

    /// The mission name written on records.
    pub fn mission(&self) -> Option<&str> {
        self.mission.as_deref()
    }

    /// The call at `call_site` of `task`: its label and source line.
    fn call(&self, task: Option<String>, call_site: Option<u32>) -> Call {
        let (label, src) = call_site.and_then(|c| self.calls.get(&c)).cloned().unwrap_or_default();
        Call { task, call_site, label, src }
    }

    /// The record of an output.
    pub fn record(&self, out: &Output) -> Record {
        let kind = match out {
            Output::Send { action, .. } => RecordKind::Action {
                seq: action.seq,
                action: action.action.clone(),
                primitive: action.primitive.clone(),
                command: action.command.clone(),
                params: action.params.clone(),
                call: self.call(action.task.clone(), action.call_site),
                queued: false,
            },
            Output::Fired { transition, call_site, .. } => {
                let mut ends = self.timeouts[transition.index()].then_some(Ends::Timeout);
                let mut src = None;
                if let Some((kind, at)) = self.handlers.get(&transition.index()) {
                    let (end, what) = match kind {
                        mcl_net::HandlerKind::Catch => (Ends::Catch, "the catch"),
                        mcl_net::HandlerKind::Condition => (Ends::Condition, "the condition of the monitor"),
                    };
                    ends = Some(end);
                    src = at.clone();
                    let via = match at {
                        Some(s) => format!("{what} at {s}"),
                        None => what.to_string(),
                    };
                    *self.last_handler.borrow_mut() = Some(via);
                }
                let label = call_site.and_then(|c| self.calls.get(&c)).and_then(|(l, _)| l.clone());
                let task = self.tasks[transition.index()].clone();
                RecordKind::Fire {
                    transition: self.ids[transition.index()].clone(),
                    call: Call { task, call_site: *call_site, label, src },
                    ends,
                }
            }
            Output::Event { event, transition, call_site, activation, .. } => {
                let task = self.tasks[transition.index()].clone();
                RecordKind::Event {
                    event: event.clone(),
                    transition: self.ids[transition.index()].clone(),
                    ends: self.ends(task.as_deref(), event),
                    call: self.call(task, *call_site),
                    activation: *activation,
                }
            }
            Output::Stale { event, activation, reason, .. } => {
                RecordKind::StaleEvent { event: event.clone(), reason: reason.clone(), activation: *activation }
            }
            Output::Unexpected { event, reason, .. } => {
                RecordKind::UnexpectedEvent { event: event.clone(), reason: reason.to_string() }
            }
            Output::Timer { transition, deadline, .. } => RecordKind::Timer {
                transition: self.ids[transition.index()].clone(),
                task: self.tasks[transition.index()].clone(),
                deadline: round_time(*deadline),
            },
            Output::Perception { name, value, .. } => {
                RecordKind::Perception { name: name.clone(), value: value.clone() }
            }
            Output::Warning { message, .. } => RecordKind::Warning { message: message.clone() },
            Output::Outcome { outcome, reason, .. } => RecordKind::Outcome {
                result: outcome.as_str().to_string(),
                reason: reason.clone(),
                via: self.last_handler.borrow().clone(),
            },
        };
        Record { mission: self.mission.clone(), ..Record::new(out.time(), kind) }
    }
}

/// The live-log line of a record (None for records not shown: fires and
/// timers unless `verbose`, poses, kinds this version does not know).
pub fn live_line(r: &Record, verbose: bool) -> Option<String> {
    let (what, call) = match &r.kind {
        RecordKind::Action { action, primitive, command, params, call, queued, .. } => {
            let params: Vec<String> = params.iter().map(|(k, v)| format!("{k}={v}")).collect();
            let queued = if *queued { "  (queued: the AAC is not connected)" } else { "" };
            (format!("action   {primitive} {command}({})  [{action}]{queued}", params.join(", ")), Some(call))
        }
        RecordKind::Event { event, ends, call, .. } => {
            let ends = match ends {
                Some(Ends::Ok) => "  (ends ok)",
                Some(Ends::Fail) => "  (ends fail)",
                _ => "",
            };
            (format!("event    {event}{ends}"), Some(call))
        }
        RecordKind::UnexpectedEvent { event, reason } => (format!("UNEXPECTED event {event} ({reason})"), None),
        RecordKind::StaleEvent { event, reason, .. } => (format!("stale    {event} ignored ({reason})"), None),
        RecordKind::Link { message } => (format!("link     {message}"), None),
        RecordKind::Perception { name, value } => (format!("percept  {name} = {value}"), None),
        RecordKind::Warning { message } => (format!("warning  {message}"), None),
        RecordKind::CoordReject { message } => (format!("REFUSED  coordination: {message}"), None),
        RecordKind::Operator { command } => (
            match command {
                crate::operator::Command::Answer { event } => format!("OPERATOR answers {event}"),
                c => format!(
                    "OPERATOR {}",
                    serde_json::to_value(c)
                        .ok()
                        .and_then(|v| v["command"].as_str().map(str::to_uppercase))
                        .unwrap_or_default()
                ),
            },
            None,
        ),
        RecordKind::Outcome { result, reason, via } => (
            format!(
                "MISSION {}{}{}",
                result.to_uppercase(),
                reason.as_ref().map(|x| format!(": {x}")).unwrap_or_default(),
                via.as_ref().map(|v| format!(" (through {v})")).unwrap_or_default()
            ),
            None,
        ),
        RecordKind::CoordSend { seq, transition, to } => (format!("send     {transition} -> {to}  (#{seq})"), None),
        RecordKind::CoordReceive { seq, transition, from, .. } => {
            (format!("receive  {from}/{transition}  (#{seq})"), None)
        }
        RecordKind::LinkLost { to, seq, what, reason } => {
            (format!("LOST     {what} -> {to}  (#{seq}, {reason})"), None)
        }
        RecordKind::LinkSend { to, seq, what, attempt, .. } if *attempt > 1 => {
            (format!("resend   {what} -> {to}  (#{seq}, attempt {attempt})"), None)
        }
        RecordKind::CoordSummary { result, messages, .. } => {
            (format!("ALL MISSIONS {}: {messages} coordination messages sent", result.to_uppercase()), None)
        }
        RecordKind::Fire { ends: Some(Ends::Catch), call, .. } => {
            ("CATCH    the try block failed: its catch starts".to_string(), Some(call))
        }
        RecordKind::Fire { ends: Some(Ends::Condition), call, .. } => {
            ("CONDITION of a monitor ended: its watched block stops, its do block runs".to_string(), Some(call))
        }
        RecordKind::Fire { ends: Some(Ends::Timeout), transition, call } => {
            (format!("TIME-OUT {transition}"), Some(call))
        }
        RecordKind::Fire { transition, call, .. } if verbose => (format!("fire     {transition}"), Some(call)),
        RecordKind::Timer { transition, task, deadline } if verbose => {
            let line = format!("timer    {transition} until {deadline:.3}");
            return Some(with_call(r, line, Some(&Call { task: task.clone(), ..Call::default() })));
        }
        _ => return None,
    };
    Some(with_call(r, what, call))
}

/// `[time] mission: what`, then the call's task, label and source line.
fn with_call(r: &Record, what: String, call: Option<&Call>) -> String {
    let mut line = format!("[{:>10.3}] ", r.t);
    if let Some(m) = r.mission.as_deref().filter(|m| *m != "*") {
        line.push_str(&format!("{m}: "));
    }
    line.push_str(&what);
    if let Some(c) = call {
        if let Some(task) = &c.task {
            line.push_str(&format!("  task={task}"));
        }
        if let Some(l) = &c.label {
            line.push_str(&format!(":{l}"));
        }
        if let Some(src) = &c.src {
            line.push_str(&format!("  at {src}"));
        }
    }
    line
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
        let last = matches!(r.kind, RecordKind::Outcome { .. } | RecordKind::CoordSummary { .. });
        self.write_line(last, r)
    }

    /// Appends one record given as JSON (`mcl plan --run`'s records).
    pub fn write_json(&mut self, r: &Value) -> std::io::Result<()> {
        let last = Record::deserialize(r)
            .is_ok_and(|r| matches!(r.kind, RecordKind::Outcome { .. } | RecordKind::CoordSummary { .. }));
        self.write_line(last, r)
    }

    /// Appends `r`; flushes when it is an outcome (`last`) or the buffer is full.
    fn write_line(&mut self, last: bool, r: &impl Serialize) -> std::io::Result<()> {
        let mut line = serde_json::to_vec(r)?;
        line.push(b'\n');
        let mut p = self.pending();
        p.buf.extend_from_slice(&line);
        if p.buf.len() >= FLUSH_BYTES || last {
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
        let r = Record::warning(1.0, "w".into());
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
        w.write(&Record::warning(0.0, "w".into())).unwrap();
        w.write(&Record::outcome(0.5, "ok", None)).unwrap();
        assert_eq!(read_trace(&path).unwrap().len(), 2, "flushed at the outcome");
        w.write(&Record::warning(1.0, "w".into())).unwrap();
        std::thread::sleep(FLUSH_EVERY * 2 + std::time::Duration::from_millis(200));
        assert_eq!(read_trace(&path).unwrap().len(), 3, "flushed by the timer");
        w.write(&Record::warning(2.0, "w".into())).unwrap();
        let f = w.flusher();
        f.flush();
        assert_eq!(read_trace(&path).unwrap().len(), 4, "flushed by a flusher");
        drop(w);
        f.flush();
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn kinds_this_version_does_not_know_are_read_and_ignored() {
        let text = "{\"t\":1.0,\"kind\":\"plan\",\"plan\":1,\"steps\":[\"a\"]}\n{\"t\":2.0,\"kind\":\"link\",\"message\":\"up\"}\n";
        let rs = parse_trace(text).unwrap();
        assert_eq!(rs[0].kind, RecordKind::Other);
        assert_eq!(rs[1].kind, RecordKind::Link { message: "up".into() });
        assert!(live_line(&rs[0], true).is_none());
    }

    #[test]
    fn operator_records_read_back() {
        let r = Record::new(
            2.5,
            RecordKind::Operator { command: crate::operator::Command::Answer { event: "evOk".into() } },
        );
        let line = serde_json::to_string(&r).unwrap();
        assert_eq!(line, r#"{"t":2.5,"kind":"operator","command":"answer","event":"evOk"}"#);
        assert_eq!(parse_trace(&format!("{line}\n")).unwrap(), vec![r.clone()]);
        assert_eq!(live_line(&r, false).unwrap(), "[     2.500] OPERATOR answers evOk");
        let p = Record::new(1.0, RecordKind::Operator { command: crate::operator::Command::Pause });
        assert_eq!(live_line(&p, false).unwrap(), "[     1.000] OPERATOR PAUSE");
    }

    #[test]
    fn a_known_kind_without_its_fields_is_an_error() {
        let err = parse_trace("{\"t\":1.0,\"kind\":\"action\",\"seq\":1}\n").unwrap_err();
        assert!(err.starts_with("1: ") && err.contains("missing field"), "{err}");
    }
}
