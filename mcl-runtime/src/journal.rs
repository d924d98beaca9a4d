//! The journal: what a player needs to survive a crash (`mcl run --journal
//! FILE`, `mcl run --resume FILE`).
//!
//! A journal is a JSONL file. Its first line is a [`Entry::Header`] (seed,
//! symbols, mission, a fingerprint of the net, the scenario of an in-process
//! mock). Then, for every input the player handled, in order, the input
//! ([`Entry::Start`], [`Entry::Event`], [`Entry::Perception`],
//! [`Entry::Timer`]) followed by the transitions it fired ([`Entry::Fire`]).
//! The entries of one input are written and the file is `fsync`ed *before*
//! the actions of that input are sent: an action is never sent that the
//! journal does not explain, and an input whose actions went out is never
//! lost. [`Entry::Ack`] records the actions the AAC acknowledged (not
//! synced: losing one only re-sends an action, which the AAC drops by its
//! `seq`).
//!
//! Against a TCP AAC (version 2), each event and perception is journaled
//! with its number `n` in the AAC's session, and [`Entry::Session`] records
//! the session the following numbers belong to (synced when it changes).
//! A resumed player tells the AAC the session and the last number it
//! journaled ([`Replayed::resume_point`]), and the AAC sends again every
//! event after it: nothing the AAC sent is lost, and nothing is handled
//! twice. [`Entry::Restart`] is the input that re-established the running
//! primitives when the AAC came back with another session (it lost its
//! memory: [`Player::reestablish`]).
//!
//! The player is deterministic for a seed and a sequence of inputs, so
//! resuming ([`replay`]) feeds the journaled inputs again, at their
//! journaled times, to a fresh player with the journaled seed: this restores
//! the exact marking, bindings, pending timers (with their deadlines), the
//! random generator and the action counter. Each input's firings are checked
//! against the journal; any difference (another net, another seed) stops the
//! resume with an error. The mission clock then continues from the time of
//! the last journaled input: the time the player was down does not count
//! (a pending timer keeps the remaining time it had at that input).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::link::{Action, Inbound};
use crate::player::{Output, Player};

/// Journal format version. Version 2 added event numbers (`n`),
/// [`Entry::Session`] and [`Entry::Restart`]; a version 1 journal is still
/// read, and resumed as before (without a resume point for the AAC).
pub const VERSION: u32 = 2;

/// The oldest journal version this player reads.
pub const OLDEST_VERSION: u32 = 1;

/// One line of a journal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "j", rename_all = "snake_case")]
pub enum Entry {
    /// First line: how the run was set up.
    Header {
        /// [`VERSION`].
        version: u32,
        /// Mission name.
        mission: String,
        /// Player seed.
        seed: u64,
        /// [`fingerprint`] of the net.
        fingerprint: String,
        /// Symbol table of the run.
        #[serde(default)]
        symbols: BTreeMap<String, Value>,
        /// Scenario text of the in-process mock, if any.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scenario: Option<String>,
        /// Seed of the mock.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mock_seed: Option<u64>,
        /// Run id given to a TCP AAC (the same run id resumes its session).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        run: Option<String>,
        /// Wall-clock start, seconds since the Unix epoch (informative).
        #[serde(default)]
        unix_start: f64,
    },
    /// The mission started.
    Start {
        /// Mission time.
        t: f64,
    },
    /// An event was received.
    Event {
        /// Mission time.
        t: f64,
        /// Event name.
        event: String,
        /// The activation it named, if any.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        activation: Option<u64>,
        /// Its number in the AAC's session, if the AAC numbered it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        n: Option<u64>,
    },
    /// A perception was received.
    Perception {
        /// Mission time.
        t: f64,
        /// Name.
        name: String,
        /// Value.
        value: Value,
        /// Its number in the AAC's session, if the AAC numbered it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        n: Option<u64>,
    },
    /// The AAC welcomed the run in this session: the numbers `n` of the
    /// entries that follow are in it. Written when the session changes.
    Session {
        /// The AAC's session id.
        id: String,
    },
    /// The AAC came back with another session (it lost its memory): the
    /// player re-established its running primitives (an input).
    Restart {
        /// Mission time.
        t: f64,
    },
    /// The player was woken for its timers.
    Timer {
        /// Mission time.
        t: f64,
    },
    /// A transition fired.
    Fire {
        /// Mission time.
        t: f64,
        /// Transition id.
        transition: String,
    },
    /// The AAC acknowledged an action.
    Ack {
        /// Its sequence number.
        seq: u64,
    },
    /// Coordination messages delivered together ([`Player::on_events`]).
    Events {
        /// Mission time.
        t: f64,
        /// Their events (`from/transition`), in the order of the inbox.
        events: Vec<String>,
    },
    /// A coordination message was sent (informative: resuming derives the
    /// messages from the firings, `coord_ended` and `coord_served`).
    CoordSend {
        /// Mission time.
        t: f64,
        /// Receiving mission.
        to: String,
        /// Transition fired.
        transition: String,
        /// Its sequence number on the link to `to`.
        seq: u64,
    },
    /// A coordination message was received (synced before it is
    /// acknowledged).
    CoordReceive {
        /// Mission time.
        t: f64,
        /// Sending mission.
        from: String,
        /// Transition it fired.
        transition: String,
        /// Its sequence number on the link from `from`.
        seq: u64,
        /// Mission time of the firing at the sender.
        sent_t: f64,
    },
    /// Once the mission had ended, its supervisor places served the
    /// messages of the inbox (a holder lends its mutex).
    CoordServed {
        /// Mission time.
        t: f64,
    },
    /// The vehicle told its peers that its mission ended.
    CoordEnded {
        /// Mission time.
        t: f64,
    },
    /// An operator's command (informative: an `abort` or an `answer` is
    /// followed by the event input it became, which resuming replays).
    Operator {
        /// Mission time.
        t: f64,
        /// The command.
        #[serde(flatten)]
        command: crate::operator::Command,
    },
}

/// An input of the player.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// Start the mission.
    Start(f64),
    /// An event, with the activation it names (the `seq` of the action
    /// that started the primitive run that raised it), if any.
    Event(f64, String, Option<u64>),
    /// A perception.
    Perception(f64, String, Value),
    /// Timers.
    Timer(f64),
    /// The vehicle lost its memory: re-establish what runs
    /// ([`Player::reestablish`]).
    Restart(f64),
    /// Coordination messages (their events) delivered together.
    Events(f64, Vec<String>),
}

impl Input {
    /// Its journal entry.
    pub fn entry(&self) -> Entry {
        self.entry_numbered(None)
    }

    /// Its journal entry, with the number `n` the AAC gave the event or
    /// perception.
    pub fn entry_numbered(&self, n: Option<u64>) -> Entry {
        match self {
            Input::Start(t) => Entry::Start { t: *t },
            Input::Event(t, e, a) => Entry::Event { t: *t, event: e.clone(), activation: *a, n },
            Input::Perception(t, name, v) => Entry::Perception { t: *t, name: name.clone(), value: v.clone(), n },
            Input::Timer(t) => Entry::Timer { t: *t },
            Input::Restart(t) => Entry::Restart { t: *t },
            Input::Events(t, events) => Entry::Events { t: *t, events: events.clone() },
        }
    }

    /// The input of a journal entry (None for other entries).
    pub fn of_entry(e: &Entry) -> Option<Input> {
        Some(match e {
            Entry::Start { t } => Input::Start(*t),
            Entry::Event { t, event, activation, .. } => Input::Event(*t, event.clone(), *activation),
            Entry::Perception { t, name, value, .. } => Input::Perception(*t, name.clone(), value.clone()),
            Entry::Timer { t } => Input::Timer(*t),
            Entry::Restart { t } => Input::Restart(*t),
            Entry::Events { t, events } => Input::Events(*t, events.clone()),
            _ => return None,
        })
    }

    /// Applies it to a player.
    pub fn apply(&self, p: &mut Player) -> Vec<Output> {
        match self {
            Input::Start(t) => p.start(*t),
            Input::Event(t, e, a) => p.on_event_from(*t, e, *a),
            Input::Perception(t, n, v) => p.on_perception(*t, n, v.clone()),
            Input::Timer(t) => p.on_timer(*t),
            Input::Restart(t) => p.reestablish(*t),
            Input::Events(t, events) => p.on_events(*t, events.clone()).0,
        }
    }

    /// The message a vehicle sent for this input, if it is one.
    pub fn message(&self) -> Option<Inbound> {
        match self {
            Input::Event(_, e, a) => Some(Inbound::Event { event: e.clone(), activation: *a, n: None }),
            Input::Perception(_, n, v) => Some(Inbound::Perception { name: n.clone(), value: v.clone(), n: None }),
            _ => None,
        }
    }

    /// Its time.
    pub fn time(&self) -> f64 {
        match self {
            Input::Start(t)
            | Input::Event(t, _, _)
            | Input::Perception(t, _, _)
            | Input::Timer(t)
            | Input::Restart(t) => *t,
            Input::Events(t, _) => *t,
        }
    }
}

/// A 64-bit FNV-1a fingerprint of the net's PNML, in hex.
pub fn fingerprint(net: &mcl_net::Net) -> String {
    let text = mcl_net::write_pnml(net).unwrap_or_default();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Appends entries to a journal file.
pub struct JournalWriter {
    file: File,
    path: PathBuf,
    buf: Vec<u8>,
}

impl JournalWriter {
    /// Creates (truncates) a journal and writes its header, synced.
    pub fn create(path: &Path, header: &Entry) -> Result<Self, String> {
        if let Some(dir) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{}`: {e}", dir.display()))?;
        }
        let file = File::create(path).map_err(|e| format!("cannot create journal `{}`: {e}", path.display()))?;
        let mut w = JournalWriter { file, path: path.to_path_buf(), buf: Vec::new() };
        w.append(header);
        w.sync()?;
        Ok(w)
    }

    /// Opens a journal to continue it, cutting an incomplete last line.
    pub fn append_to(path: &Path) -> Result<Self, String> {
        let text =
            mcl_net::input::read_bytes(path, mcl_net::input::MAX_RECORDS_BYTES).map_err(|e| format!("journal: {e}"))?;
        let keep = text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let file = OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| format!("cannot open journal `{}`: {e}", path.display()))?;
        file.set_len(keep as u64).map_err(|e| format!("cannot write journal `{}`: {e}", path.display()))?;
        let mut file = file;
        use std::io::Seek;
        file.seek(std::io::SeekFrom::End(0)).map_err(|e| e.to_string())?;
        Ok(JournalWriter { file, path: path.to_path_buf(), buf: Vec::new() })
    }

    /// Buffers an entry.
    pub fn append(&mut self, e: &Entry) {
        if serde_json::to_writer(&mut self.buf, e).is_ok() {
            self.buf.push(b'\n');
        }
    }

    /// Nothing is buffered.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Writes the buffered entries and waits until they are on disk.
    pub fn sync(&mut self) -> Result<(), String> {
        if self.buf.is_empty() {
            return Ok(());
        }
        self.file
            .write_all(&self.buf)
            .and_then(|_| self.file.sync_data())
            .map_err(|e| format!("cannot write journal `{}`: {e}", self.path.display()))?;
        self.buf.clear();
        Ok(())
    }
}

/// Reads a journal. A last line cut by a crash is ignored.
pub fn read_journal(path: &Path) -> Result<Vec<Entry>, String> {
    let text =
        mcl_net::input::read_text(path, mcl_net::input::MAX_RECORDS_BYTES).map_err(|e| format!("journal: {e}"))?;
    let complete = text.rfind('\n').map_or("", |i| &text[..=i]);
    let mut out = Vec::new();
    for (i, line) in complete.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let e: Entry = serde_json::from_str(line)
            .map_err(|e| format!("{}:{}: not a journal entry: {e}", path.display(), i + 1))?;
        out.push(e);
    }
    match out.first() {
        Some(Entry::Header { version, .. }) if (OLDEST_VERSION..=VERSION).contains(version) => Ok(out),
        Some(Entry::Header { version, .. }) => Err(format!(
            "{}: journal version {version}, this player reads versions {OLDEST_VERSION} to {VERSION}",
            path.display()
        )),
        _ => Err(format!("{}: not a journal (no header line)", path.display())),
    }
}

/// What a replay restored.
#[derive(Debug, Default)]
pub struct Replayed {
    /// Inputs replayed.
    pub inputs: usize,
    /// Actions the replayed firings sent, in order.
    pub actions: Vec<Action>,
    /// Sequence numbers the AAC acknowledged.
    pub acked: BTreeSet<u64>,
    /// Time of the last journaled input.
    pub last_time: f64,
    /// The actions up to this seq were dropped when the AAC came back with
    /// another session ([`Entry::Restart`]): never sent again.
    pub dropped_upto: u64,
    /// Where the run stands with its AAC: the last [`Entry::Session`] and
    /// the highest event number journaled in it. `None` for a version 1
    /// journal (its events carry no numbers).
    pub resume_point: Option<(Option<String>, u64)>,
}

impl Replayed {
    /// Actions to send again: those never acknowledged (nor dropped).
    pub fn unacknowledged(&self) -> Vec<Action> {
        self.actions.iter().filter(|a| a.seq > self.dropped_upto && !self.acked.contains(&a.seq)).cloned().collect()
    }
}

/// Replays the inputs of `entries` into `player` (fresh, with the journal's
/// seed and symbols), checking each input's firings against the journal.
/// `each` sees every input with the outputs it produced (to rebuild a mock
/// vehicle and the trace).
pub fn replay(
    player: &mut Player,
    entries: &[Entry],
    mut each: impl FnMut(&Input, &[Output]),
) -> Result<Replayed, String> {
    let mut r = Replay::new(entries);
    while let Some(step) = r.next(player) {
        if let Step::Input(input, out) = step? {
            each(&input, &out);
        }
    }
    Ok(r.done())
}

/// One step of a [`Replay`].
#[derive(Debug)]
pub enum Step<'a> {
    /// An input, applied, with the outputs it produced.
    Input(Input, Vec<Output>),
    /// An entry that is neither an input, a firing nor an acknowledgement
    /// (coordination messages), for the caller to apply.
    Other(&'a Entry),
}

/// A replay one entry at a time: [`replay`] for callers with state of their
/// own to rebuild in the journal's order (a coordinated vehicle's inbox and
/// messages).
pub struct Replay<'a> {
    entries: &'a [Entry],
    i: usize,
    r: Replayed,
}

impl<'a> Replay<'a> {
    /// A replay of `entries` (header included).
    pub fn new(entries: &'a [Entry]) -> Self {
        Replay { entries, i: 0, r: Replayed::default() }
    }

    /// The next step: an input is applied to `player` and its firings
    /// checked against the journal. None at the end.
    pub fn next(&mut self, player: &mut Player) -> Option<Result<Step<'a>, String>> {
        let entries = self.entries;
        loop {
            let e = entries.get(self.i)?;
            self.i += 1;
            match e {
                Entry::Ack { seq } => {
                    self.r.acked.insert(*seq);
                    continue;
                }
                Entry::Header { version, .. } => {
                    if *version >= 2 {
                        self.r.resume_point = Some((None, 0));
                    }
                    continue;
                }
                Entry::Fire { .. } => continue,
                Entry::Session { id } => {
                    if let Some(p) = &mut self.r.resume_point {
                        *p = (Some(id.clone()), 0);
                    }
                    continue;
                }
                Entry::Event { n: Some(n), .. } | Entry::Perception { n: Some(n), .. } => {
                    if let Some(p) = &mut self.r.resume_point {
                        p.1 = p.1.max(*n);
                    }
                }
                Entry::Restart { .. } => self.r.dropped_upto = player.last_seq(),
                _ => {}
            }
            let Some(input) = Input::of_entry(e) else { return Some(Ok(Step::Other(e))) };
            let mut expected: Vec<&str> = Vec::new();
            while let Some(Entry::Fire { transition, .. }) = entries.get(self.i) {
                expected.push(transition);
                self.i += 1;
            }
            let out = input.apply(player);
            let ids = player.net().transitions();
            let fired: Vec<&str> = out
                .iter()
                .filter_map(|o| match o {
                    Output::Fired { transition, .. } => Some(ids[transition.index()].id.as_str()),
                    _ => None,
                })
                .collect();
            let last = !entries[self.i..].iter().any(|e| Input::of_entry(e).is_some());
            let agrees = fired == expected || (last && fired.starts_with(&expected));
            if !agrees {
                let k = fired.iter().zip(&expected).take_while(|(a, b)| a == b).count();
                return Some(Err(format!(
                    "the journal does not match this mission: after input {} ({:?}) the journal fired `{}` where the player fires `{}` (another net, seed or symbol table?)",
                    self.r.inputs + 1,
                    input,
                    expected.get(k).copied().unwrap_or("nothing"),
                    fired.get(k).copied().unwrap_or("nothing"),
                )));
            }
            for o in &out {
                if let Output::Send { action, .. } = o {
                    self.r.actions.push(action.clone());
                }
            }
            self.r.last_time = self.r.last_time.max(input.time());
            self.r.inputs += 1;
            return Some(Ok(Step::Input(input, out)));
        }
    }

    /// What the replay restored.
    pub fn done(self) -> Replayed {
        self.r
    }
}

/// The time of the last input of a journal (0 without any): where the
/// mission clock of a resumed run starts.
pub fn last_time(entries: &[Entry]) -> f64 {
    entries.iter().filter_map(Input::of_entry).map(|i| i.time()).fold(0.0, f64::max)
}

/// Per sending mission, the last sequence number of the coordination
/// messages a journal received (they arrive in order: every smaller one was
/// received too).
pub fn received_seqs(entries: &[Entry]) -> BTreeMap<String, u64> {
    let mut out = BTreeMap::new();
    for e in entries {
        if let Entry::CoordReceive { from, seq, .. } = e {
            let last = out.entry(from.clone()).or_insert(0);
            *last = (*last).max(*seq);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::player::PlayerOptions;
    use mcl_net::{NetBuilder, Place, Transition, TransitionKind};
    use std::sync::Arc;

    /// p --(event e)--> q --(event e)--> mission.ok
    fn net() -> Arc<mcl_net::Net> {
        let mut b = NetBuilder::new("m");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q"));
        let ok = b.add_place(Place::new("mission.ok"));
        let a = b.add_transition(Transition::new("a").with_kind(TransitionKind::Event("e".into())));
        let c = b.add_transition(Transition::new("c").with_kind(TransitionKind::Event("e".into())));
        b.add_input(p, a, 1).add_output(a, q, 1);
        b.add_input(q, c, 1).add_output(c, ok, 1);
        Arc::new(b.build().unwrap())
    }

    fn header() -> Entry {
        Entry::Header {
            version: VERSION,
            mission: "m".into(),
            seed: 0,
            fingerprint: fingerprint(&net()),
            symbols: BTreeMap::new(),
            scenario: None,
            mock_seed: None,
            run: None,
            unix_start: 0.0,
        }
    }

    #[test]
    fn write_read_replay() {
        let dir = std::env::temp_dir().join(format!("mcl-journal-{}", std::process::id()));
        let path = dir.join("j.jsonl");
        let mut w = JournalWriter::create(&path, &header()).unwrap();
        w.append(&Entry::Start { t: 0.0 });
        w.append(&Entry::Event { t: 2.0, event: "e".into(), activation: None, n: None });
        w.append(&Entry::Fire { t: 2.0, transition: "a".into() });
        w.append(&Entry::Ack { seq: 1 });
        w.sync().unwrap();
        drop(w);
        // A line cut by a crash is ignored and then cut off.
        std::fs::write(&path, std::fs::read_to_string(&path).unwrap() + "{\"j\":\"eve").unwrap();
        let entries = read_journal(&path).unwrap();
        assert_eq!(entries.len(), 5);
        let mut p = Player::new(net(), PlayerOptions::default());
        let mut seen = 0;
        let r = replay(&mut p, &entries, |_, _| seen += 1).unwrap();
        assert_eq!((r.inputs, seen, r.last_time, r.acked.len()), (2, 2, 2.0, 1));
        assert_eq!(p.marking().0, vec![0, 1, 0]);
        let mut w = JournalWriter::append_to(&path).unwrap();
        w.append(&Entry::Event { t: 3.0, event: "e".into(), activation: None, n: None });
        w.sync().unwrap();
        assert_eq!(read_journal(&path).unwrap().len(), 6);

        // A journal that disagrees with the net is refused.
        let mut bad = entries.clone();
        bad[3] = Entry::Fire { t: 2.0, transition: "c".into() };
        bad.push(Entry::Event { t: 3.0, event: "e".into(), activation: None, n: None });
        let mut p = Player::new(net(), PlayerOptions::default());
        let e = replay(&mut p, &bad, |_, _| {}).unwrap_err();
        assert!(e.contains("the journal fired `c` where the player fires `a`"), "{e}");
        let _ = std::fs::remove_dir_all(dir);
    }

    /// p --(start: enable X)--> q --(event e)--> mission.ok
    fn net_with_action() -> Arc<mcl_net::Net> {
        let mut b = NetBuilder::new("m");
        let p = b.add_place(Place::new("p").with_tokens(1));
        let q = b.add_place(Place::new("q"));
        let ok = b.add_place(Place::new("mission.ok"));
        let enable = mcl_net::ActionRef {
            action: "enableX".into(),
            primitive: "XPrimitive".into(),
            command: "enable".into(),
            params: vec![],
        };
        let a = b.add_transition(Transition::new("a").with_action(enable));
        let c = b.add_transition(Transition::new("c").with_kind(TransitionKind::Event("e".into())));
        b.add_input(p, a, 1).add_output(a, q, 1);
        b.add_input(q, c, 1).add_output(c, ok, 1);
        Arc::new(b.build().unwrap())
    }

    /// Version 2: where the run stands with its AAC (the last session and
    /// the last event number journaled in it), and a restart that drops the
    /// actions sent before it and re-sends what runs.
    #[test]
    fn resume_point_and_restart() {
        let header = |v| match header() {
            Entry::Header { mission, seed, symbols, scenario, mock_seed, run, unix_start, .. } => Entry::Header {
                version: v,
                mission,
                seed,
                fingerprint: fingerprint(&net_with_action()),
                symbols,
                scenario,
                mock_seed,
                run,
                unix_start,
            },
            e => e,
        };
        let mut entries = vec![
            header(VERSION),
            Entry::Start { t: 0.0 },
            Entry::Fire { t: 0.0, transition: "a".into() },
            Entry::Session { id: "s1".into() },
            Entry::Perception { t: 1.0, name: "x".into(), value: Value::Null, n: Some(1) },
            Entry::Perception { t: 1.5, name: "x".into(), value: Value::Null, n: Some(2) },
        ];
        let mut p = Player::new(net_with_action(), PlayerOptions::default());
        let r = replay(&mut p, &entries, |_, _| {}).unwrap();
        assert_eq!(r.resume_point, Some((Some("s1".to_string()), 2)));
        assert_eq!(r.unacknowledged().iter().map(|a| a.seq).collect::<Vec<_>>(), [1]);
        // The AAC lost its state: a new session, enableX sent again as #2.
        entries.push(Entry::Session { id: "s2".into() });
        entries.push(Entry::Restart { t: 2.0 });
        entries.push(Entry::Perception { t: 3.0, name: "x".into(), value: Value::Null, n: Some(1) });
        let mut p = Player::new(net_with_action(), PlayerOptions::default());
        let r = replay(&mut p, &entries, |_, _| {}).unwrap();
        assert_eq!(r.resume_point, Some((Some("s2".to_string()), 1)));
        assert_eq!((r.dropped_upto, r.unacknowledged().iter().map(|a| a.seq).collect::<Vec<_>>()), (1, vec![2]));
        assert!(p.is_live_activation(2) && !p.is_live_activation(1));
        // A version 1 journal has no resume point.
        entries[0] = header(1);
        let mut p = Player::new(net_with_action(), PlayerOptions::default());
        assert_eq!(replay(&mut p, &entries, |_, _| {}).unwrap().resume_point, None);
    }
}
