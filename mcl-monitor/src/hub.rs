//! The records of a run and its state, shared by the run (the binary's
//! trace sink pushes every record) and the server (which answers requests
//! and pushes new records to every page).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Arc, Mutex, MutexGuard};

use mcl_runtime::operator::{self, Command};
use mcl_runtime::trace::Record;
use tokio::sync::watch;

use crate::state::{State, StateJson};

/// Whether the page follows a run or replays traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// `mcl run --monitor`: records arrive as the run makes them.
    Live,
    /// `mcl monitor TRACE...`: every record is there from the start.
    Replay,
}

/// What the operator may do: the token a request must carry, and where
/// its commands go (each vehicle of the run, by its mission's name).
struct Operator {
    token: String,
    vehicles: Vec<(String, operator::Sender)>,
}

/// Why an operator's command was refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Refused {
    /// The run takes no operator commands (no `--operator-token`, or a replay).
    Off,
    /// The request carries no token, or another one.
    Token,
    /// The run is over.
    Finished,
    /// The request names no vehicle of the run, or names none where it
    /// must (an answer in a run of several vehicles): why.
    Vehicle(String),
}

/// Records, the state they make, and who waits for new ones.
pub struct Hub {
    mode: Mode,
    title: String,
    operator: Option<Operator>,
    inner: Mutex<Inner>,
    /// The number of records and whether the run is over, watched by the
    /// pages' event streams.
    changes: watch::Sender<(usize, bool)>,
}

struct Inner {
    /// The records, as the run pushed them.
    records: Vec<Arc<Record>>,
    /// The JSON texts of the first records (serialized once, on the
    /// server's thread when a page first asks for them, then sent to every
    /// page).
    lines: Vec<Arc<str>>,
    /// When each record was pushed (milliseconds since the Unix epoch).
    pushed_ms: Vec<f64>,
    state: State,
    finished: bool,
    /// Source files read so far (None: unreadable).
    sources: BTreeMap<String, Option<Arc<str>>>,
    /// The missions' control-structure trees.
    trees: Vec<crate::tree::MissionTree>,
}

/// Milliseconds since the Unix epoch.
pub fn unix_ms() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs_f64() * 1e3).unwrap_or(0.0)
}

impl Hub {
    /// A hub for a run (`Live`) or a replay, titled `title` (the mission
    /// file, or the trace files).
    pub fn new(mode: Mode, title: String) -> Self {
        Hub {
            mode,
            title,
            operator: None,
            inner: Mutex::new(Inner {
                records: Vec::new(),
                lines: Vec::new(),
                pushed_ms: Vec::new(),
                state: State::default(),
                finished: mode == Mode::Replay,
                sources: BTreeMap::new(),
                trees: Vec::new(),
            }),
            changes: watch::channel((0, mode == Mode::Replay)).0,
        }
    }

    /// Takes operator commands that carry `token`, and sends each to the
    /// vehicle it names among `vehicles` (by mission name, each with the
    /// sending end of its commands).
    pub fn with_operator(mut self, token: String, vehicles: Vec<(String, operator::Sender)>) -> Self {
        self.operator = Some(Operator { token, vehicles });
        self
    }

    /// The vehicles that take operator commands (none without a token).
    pub fn vehicles(&self) -> Vec<String> {
        self.operator.iter().flat_map(|o| o.vehicles.iter().map(|(n, _)| n.clone())).collect()
    }

    fn inner(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds a record and wakes the pages. The run's thread only keeps it
    /// and updates the state: pages' requests serialize it (once).
    pub fn push(&self, r: &Record) {
        let r = Arc::new(r.clone());
        let n = {
            let mut i = self.inner();
            i.state.apply(&r);
            i.records.push(r);
            i.pushed_ms.push(unix_ms());
            i.records.len()
        };
        self.changes.send_modify(|c| c.0 = n);
    }

    /// Adds missions' control-structure trees (`GET /api/tree`).
    pub fn add_trees(&self, trees: impl IntoIterator<Item = crate::tree::MissionTree>) {
        self.inner().trees.extend(trees);
    }

    /// The missions' control-structure trees.
    pub fn trees(&self) -> Vec<crate::tree::MissionTree> {
        self.inner().trees.clone()
    }

    /// The files of the calls seen so far.
    pub fn files(&self) -> Vec<String> {
        let mut f: Vec<String> = self.inner().state.files().map(str::to_string).collect();
        f.sort();
        f.dedup();
        f
    }

    /// The run is over: the pages are told, operator commands are refused.
    pub fn finish(&self) {
        self.inner().finished = true;
        self.changes.send_modify(|c| c.1 = true);
    }

    /// Follow / replay.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The title of the page.
    pub fn title(&self) -> &str {
        &self.title
    }

    /// Whether operator commands can be taken (with their token).
    pub fn has_operator(&self) -> bool {
        self.operator.is_some()
    }

    /// Watches the number of records and the end of the run.
    pub fn subscribe(&self) -> watch::Receiver<(usize, bool)> {
        self.changes.subscribe()
    }

    /// Records `from..` (at most `max`) as JSON texts, with the push time
    /// of the last one.
    pub fn records(&self, from: usize, max: usize) -> (Vec<Arc<str>>, Option<f64>) {
        let (from, to, done, todo) = {
            let i = self.inner();
            let from = from.min(i.records.len());
            let to = from.saturating_add(max).min(i.records.len());
            let done = i.lines.len();
            (from, to, done, i.records[done.min(to)..to].to_vec())
        };
        // Serialized without the lock: the run goes on meanwhile.
        let new: Vec<Arc<str>> =
            todo.iter().map(|r| Arc::from(serde_json::to_string(&**r).unwrap_or_default())).collect();
        // `new` holds the records start..to; another request may have
        // cached some of them meanwhile.
        let start = done.min(to);
        let mut i = self.inner();
        let cached = i.lines.len();
        if (start..to).contains(&cached) {
            i.lines.extend(new[cached - start..].iter().cloned());
        }
        let out = (from..to).map(|k| i.lines.get(k).cloned().unwrap_or_else(|| new[k - start].clone())).collect();
        (out, to.checked_sub(1).filter(|_| to > from).map(|k| i.pushed_ms[k]))
    }

    /// The state (`GET /api/state`) and whether the run is over.
    pub fn state(&self) -> (StateJson, bool) {
        let i = self.inner();
        (i.state.json(), i.finished)
    }

    /// The text of `file` when a call of the run is written in it (no other
    /// file is served), read once.
    pub fn source(&self, file: &str) -> Option<Arc<str>> {
        let mut i = self.inner();
        if let Some(s) = i.sources.get(file) {
            return s.clone();
        }
        if !i.state.files().any(|f| f == file) {
            return None;
        }
        let text = mcl_net::input::read_source(Path::new(file)).ok().map(Arc::from);
        i.sources.insert(file.to_string(), text.clone());
        text
    }

    /// Passes an operator's command to the run when `token` is the run's:
    /// to `vehicle`, or, when it names none, to the only vehicle, or to
    /// every vehicle (but an answer, which is for one primitive of one
    /// vehicle).
    pub fn command(&self, token: Option<&str>, vehicle: Option<&str>, c: Command) -> Result<(), Refused> {
        let op = self.operator.as_ref().ok_or(Refused::Off)?;
        if !token.is_some_and(|t| same(t.as_bytes(), op.token.as_bytes())) {
            return Err(Refused::Token);
        }
        if self.inner().finished {
            return Err(Refused::Finished);
        }
        let names = || op.vehicles.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ");
        let to: Vec<&operator::Sender> = match vehicle {
            Some(v) => match op.vehicles.iter().find(|(n, _)| n == v) {
                Some((_, tx)) => vec![tx],
                None => return Err(Refused::Vehicle(format!("no vehicle `{v}` in this run (vehicles: {})", names()))),
            },
            None if op.vehicles.len() > 1 && matches!(c, Command::Answer { .. }) => {
                return Err(Refused::Vehicle(format!(
                    "an answer is for one vehicle: name it with \"vehicle\" (vehicles: {})",
                    names()
                )))
            }
            None => op.vehicles.iter().map(|(_, tx)| tx).collect(),
        };
        // A vehicle's side is gone once its run is over.
        let sent = to.iter().filter(|tx| tx.send(c.clone()).is_ok()).count();
        if sent == 0 {
            return Err(Refused::Finished);
        }
        Ok(())
    }
}

/// Compares two secrets in time that depends on their lengths only.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// A hub shared by the run and the server.
pub type SharedHub = Arc<Hub>;

#[cfg(test)]
mod tests {
    use super::*;
    use mcl_runtime::trace::RecordKind;

    #[test]
    fn commands_need_the_token_and_a_running_run() {
        let (tx, mut rx) = operator::channel();
        let hub = Hub::new(Mode::Live, "t".into()).with_operator("s3cret".into(), vec![("m".into(), tx)]);
        assert_eq!(hub.command(None, None, Command::Pause), Err(Refused::Token));
        assert_eq!(hub.command(Some("s3creT"), None, Command::Pause), Err(Refused::Token));
        assert_eq!(hub.command(Some("s3cret"), None, Command::Pause), Ok(()));
        assert_eq!(rx.try_recv().unwrap(), Command::Pause);
        hub.finish();
        assert_eq!(hub.command(Some("s3cret"), None, Command::Abort), Err(Refused::Finished));
        let off = Hub::new(Mode::Replay, "t".into());
        assert_eq!(off.command(Some("s3cret"), None, Command::Abort), Err(Refused::Off));
    }

    #[test]
    fn commands_go_to_the_vehicle_named_or_to_every_vehicle() {
        let (ta, mut ra) = operator::channel();
        let (tb, mut rb) = operator::channel();
        let hub = Hub::new(Mode::Live, "t".into()).with_operator("k".into(), vec![("a".into(), ta), ("b".into(), tb)]);
        assert_eq!(hub.vehicles(), ["a", "b"]);
        assert_eq!(hub.command(Some("k"), Some("b"), Command::Pause), Ok(()));
        assert_eq!((ra.try_recv().ok(), rb.try_recv().ok()), (None, Some(Command::Pause)));
        assert_eq!(hub.command(Some("k"), None, Command::Abort), Ok(()));
        assert_eq!((ra.try_recv().ok(), rb.try_recv().ok()), (Some(Command::Abort), Some(Command::Abort)));
        let answer = Command::Answer { event: "e".into() };
        assert!(matches!(hub.command(Some("k"), None, answer.clone()), Err(Refused::Vehicle(_))));
        assert!(matches!(hub.command(Some("k"), Some("c"), Command::Pause), Err(Refused::Vehicle(_))));
        assert_eq!(hub.command(None, Some("c"), Command::Pause), Err(Refused::Token), "the token first");
        assert_eq!(hub.command(Some("k"), Some("a"), answer.clone()), Ok(()));
        assert_eq!(ra.try_recv().ok(), Some(answer));
    }

    #[test]
    fn records_are_kept_in_order_and_counted() {
        let hub = Hub::new(Mode::Live, "t".into());
        let rx = hub.subscribe();
        hub.push(&Record::warning(1.0, "a".into()));
        hub.push(&Record::new(2.0, RecordKind::Link { message: "b".into() }));
        assert_eq!(*rx.borrow(), (2, false));
        let (lines, pushed) = hub.records(1, 10);
        assert_eq!(lines.len(), 1);
        assert!(lines[0].contains("\"link\"") && pushed.is_some());
        assert!(hub.records(5, 10).0.is_empty());
        let (all, _) = hub.records(0, 10);
        assert_eq!(all.len(), 2);
        assert!(all[0].contains("\"warning\"") && Arc::ptr_eq(&all[1], &lines[0]), "serialized once");
        assert_eq!(hub.state().0.t, 2.0);
        assert!(hub.source("/etc/passwd").is_none(), "only the files of calls are served");
    }
}
