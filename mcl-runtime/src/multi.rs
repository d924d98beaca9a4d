//! Several coordinated vehicles at once (seed 6.3-6.4, `docs/coordination.md`).
//!
//! Each [`Vehicle`] is a player on its vehicle net (its mission with its part
//! of the supervisors), its own in-process mock vehicle and its end of a
//! [`CoordTransport`]. After every input, each firing of a transition listed
//! in the net's `coord.send` property becomes a [`CoordMessage`] to each
//! mission it names (trace record `coord_send`); a message received
//! (`coord_receive`) is kept in the vehicle's inbox until its event
//! ([`CoordMessage::event`]) is awaited by an enabled receive transition, and
//! is then fed to the player as that event (never dropped: a mutex copy may
//! have to give its token back first). The messages waiting in an inbox are
//! fed together ([`Player::on_events`]): they are firings that happened
//! before the vehicle reacts, so its net settles only once it has taken them
//! all (otherwise two vehicles woken by one release of a mutex could both
//! take it).
//!
//! * [`run_virtual`]: the discrete-event loop of [`crate::virtual_loop`]
//!   over every vehicle's timers and vehicle (the mock, a simulated one:
//!   any [`VirtualVehicle`]), in virtual time. Deterministic for a seed, whatever the transport:
//!   after each input the loop waits until the messages it sent have reached
//!   their receivers, and delivers them at the same virtual instant, before
//!   anything else happens, one receiving vehicle at a time, each reaction's
//!   messages delivered before the next vehicle takes its own (the
//!   synchronous communication that keeps the copies of a supervisor equal).
//!   Vehicles start one after the other, each with the messages of the
//!   previous ones' first firings already applied to its initial marking. At equal times vehicles go in the order
//!   given, a player's timers before its mock's messages. A vehicle given a
//!   start time ([`Vehicle::starting_at`]: a counterexample scenario's
//!   `[counterexample.start]`) begins its mission then: until that instant
//!   its player and its vehicle do nothing, and the messages it receives
//!   wait in its inbox (applied at its start, as above).
//!   [`run_virtual_with_link`] carries the messages over a modelled
//!   acoustic link instead ([`crate::acoustic`]): each arrives when the link
//!   delivers it (delays, losses, retransmissions), an event of the same
//!   loop.
//! * [`run_real_time`]: one tokio task per vehicle, each sleeping until its
//!   next timer or mock message and waking for messages; a message is
//!   delivered as soon as it arrives. The run ends when every mission has
//!   ended, when nothing can happen any more (every vehicle without timers
//!   nor pending mock messages, no message in flight: the unfinished
//!   missions are stuck), or at the time limit.
//!
//! Every record names its mission; the last one, `coord_summary`, gives
//! the number of messages sent and names every mission as `"*"`.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::acoustic::{AcousticLink, Channel};
use crate::clock::Clock;
use crate::coord::{send_table, token_table, CoordMessage, CoordTransport, Incoming, MutexMessages, TokenMutex};
use crate::driver::{drain_poses, feed_mock, perception_or_event, End, Limits, Session, Sink};
use crate::journal::{Entry, Input, JournalWriter, Replay, Step};
use crate::operator::{self, Command};
use crate::player::{Outcome, Output, Player, PlayerOptions};
use crate::trace::{Record, RecordKind, Tracer};
use crate::vehicle::VirtualVehicle;
use crate::virtual_loop::{self, Discrete, Stop};
use mcl_net::semantics::{fire, is_enabled, is_enabled_with};
use mcl_net::wire::Codebook;
use mcl_net::{Marking, Net};

/// How long virtual time waits for a message to cross the transport.
pub const DELIVERY_TIMEOUT: Duration = Duration::from_secs(30);

/// How long a vehicle whose run is over still waits for its peers to
/// acknowledge the messages it sent them (a peer that restarts meanwhile
/// gets them).
pub const FLUSH_TIMEOUT: Duration = Duration::from_secs(10);

/// A sink shared by the sessions of several vehicles.
pub type SharedSink = Arc<Mutex<dyn Sink + Send>>;

struct SharedHandle(SharedSink);

impl Sink for SharedHandle {
    fn record(&mut self, r: &Record) {
        if let Ok(mut s) = self.0.lock() {
            s.record(r);
        }
    }
    fn wants_records(&self) -> bool {
        self.0.lock().map(|s| s.wants_records()).unwrap_or(false)
    }
    fn replaying(&mut self, on: bool) {
        if let Ok(mut s) = self.0.lock() {
            s.replaying(on);
        }
    }
}

/// One vehicle of a coordinated run.
pub struct Vehicle {
    name: String,
    player: Player,
    opts: PlayerOptions,
    tracer: Tracer,
    mock: Box<dyn VirtualVehicle + Send>,
    transport: Box<dyn CoordTransport>,
    sends: HashMap<String, Vec<String>>,
    tokens: Vec<TokenMutex>,
    journal: Option<JournalWriter>,
    resume: Option<Vec<Entry>>,
    crash_after: Option<u64>,
    start_at: f64,
    delays: Vec<(String, u64, f64)>,
    operator: Option<operator::Receiver>,
}

impl Vehicle {
    /// A vehicle named `name` playing `net` (its tracer should name it
    /// too) against `mock` (the mock vehicle, a simulated one). Reads the
    /// send table from the net's `coord.send` property and calls
    /// `mock.initial()`.
    pub fn new(
        name: &str,
        net: Arc<Net>,
        opts: PlayerOptions,
        tracer: Tracer,
        mock: impl VirtualVehicle + Send + 'static,
        transport: Box<dyn CoordTransport>,
    ) -> Result<Self, String> {
        let sends = send_table(&net)?;
        let tokens = token_table(&net)?;
        let mut mock: Box<dyn VirtualVehicle + Send> = Box::new(mock);
        mock.initial();
        let player = Player::new(net, opts.clone());
        Ok(Vehicle {
            name: name.to_string(),
            player,
            opts,
            tracer,
            mock,
            transport,
            sends,
            tokens,
            journal: None,
            resume: None,
            crash_after: None,
            start_at: 0.0,
            delays: Vec::new(),
            operator: None,
        })
    }

    /// Takes an operator's commands from `commands` (`mcl run
    /// --operator-token`, docs/monitor.md): in [`run_real_time`] the
    /// vehicle alone pauses (it takes no input and its mission time stands
    /// still), resumes, aborts (its abort hook, [`operator::with_abort_hook`])
    /// or takes an answer (an abort ends its pause); in [`run_virtual_paced`]
    /// a pause stops the whole fleet (one clock). Commands are traced and
    /// journaled as in a single run.
    pub fn with_operator(mut self, commands: operator::Receiver) -> Self {
        self.operator = Some(commands);
        self
    }

    /// The vehicle's mission begins at `t` seconds of virtual time
    /// ([`run_virtual`]; 0, the default: at once), not before.
    pub fn starting_at(mut self, t: f64) -> Self {
        self.start_at = if t.is_finite() { t.max(0.0) } else { 0.0 };
        self
    }

    /// In [`run_virtual`] without a modelled link, the vehicle's message
    /// number `seq` to mission `to` (numbered from 1 per receiver, as
    /// [`CoordMessage::seq`]) reaches `to` only at `until` seconds of
    /// virtual time (a counterexample scenario's `[[counterexample.delay]]`:
    /// a late message of a real link), and the later messages to `to`
    /// after it (delivered in order).
    pub fn delaying(mut self, to: &str, seq: u64, until: f64) -> Self {
        if until.is_finite() {
            self.delays.push((to.to_string(), seq, until));
        }
        self
    }

    /// Journals the vehicle's inputs, firings and messages in `journal`
    /// (real time only), after replaying `resume` (the entries of the same
    /// journal, read before it was opened to append) when given;
    /// `crash_after` is the test hook of [`Session::crash_after`].
    pub fn with_journal(
        mut self,
        journal: JournalWriter,
        resume: Option<Vec<Entry>>,
        crash_after: Option<u64>,
    ) -> Self {
        self.journal = Some(journal);
        self.resume = resume;
        self.crash_after = crash_after;
        self
    }

    /// The mission name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

/// How a coordinated run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiEnd {
    /// Per mission, in the order given: its end and its last time.
    pub ends: Vec<(String, End, f64)>,
    /// Coordination messages sent.
    pub messages: u64,
    /// Firings per mission (same order).
    pub fired: Vec<u64>,
    /// Of the messages sent, those of the single-holder mutex protocol.
    pub mutex: MutexMessages,
}

impl MultiEnd {
    /// The worst exit status of the missions (0 ok, 1 fail, 3 stuck or time limit).
    pub fn exit_code(&self) -> u8 {
        self.ends.iter().map(|(_, e, _)| e.exit_code()).max().unwrap_or(0)
    }

    /// `ok` when every mission is, else the worst result.
    pub fn result(&self) -> &'static str {
        self.ends.iter().map(|(_, e, _)| e).max_by_key(|e| e.exit_code()).map_or("ok", |e| {
            if e.exit_code() == 0 {
                "ok"
            } else {
                e.result()
            }
        })
    }
}

/// A vehicle while it runs.
struct Live<'a> {
    name: String,
    s: Session<'a>,
    opts: PlayerOptions,
    mock: Box<dyn VirtualVehicle + Send>,
    transport: Box<dyn CoordTransport>,
    sends: HashMap<String, Vec<String>>,
    inbox: VecDeque<CoordMessage>,
    /// The last sequence number sent to each mission.
    seq: HashMap<String, u64>,
    end: Option<End>,
    /// Mutexes held by other vehicles, with the requests not yet granted.
    tokens: Vec<(TokenMutex, u32)>,
    mutex: MutexMessages,
    /// Once the mission has ended: the marking, whose supervisor places
    /// still serve the other vehicles (a holder still lends its mutex).
    after_end: Option<Marking>,
    /// Rebuilding the state from the journal: messages are kept in
    /// `resend` instead of being sent, nothing is journaled.
    replaying: bool,
    resend: Vec<CoordMessage>,
    /// [`ENDED`] was sent to the peers.
    ended_sent: bool,
    /// [`ENDED`] messages received.
    peers_ended: usize,
    /// When its mission begins (virtual time).
    start_at: f64,
    /// Its messages delivered late ([`Vehicle::delaying`]).
    delays: Vec<(String, u64, f64)>,
}

impl Live<'_> {
    /// The consequences of `outs` (the outputs of the last input): asks for
    /// or gives back the tokens of mutexes held by other vehicles
    /// ([`Live::arbitrate`], new inputs), journals the messages that the
    /// firings require and syncs the journal, then feeds the actions to the
    /// mock and sends the messages. Returns the messages.
    fn after(&mut self, outs: &[Output]) -> Result<Vec<CoordMessage>, String> {
        let mut sent = self.messages_for(outs)?;
        let mut all = outs.to_vec();
        let now = self.s.player.now();
        for event in self.arbitrate(&mut sent)? {
            let outs = self.s.step(Input::Event(now, event, None))?;
            sent.extend(self.messages_for(&outs)?);
            all.extend(outs);
        }
        self.commit(&all, sent)
    }

    /// Syncs the journal, then lets the actions of `outs` and the messages
    /// `sent` leave (kept for later while replaying).
    fn commit(&mut self, outs: &[Output], mut sent: Vec<CoordMessage>) -> Result<Vec<CoordMessage>, String> {
        self.s.sync()?;
        let now = self.s.player.now();
        feed_mock(&mut self.s, &mut *self.mock, now, outs);
        for m in &sent {
            if self.replaying {
                self.resend.push(m.clone());
            } else {
                self.transport.send(m.clone())?;
            }
        }
        sent.retain(|m| m.transition != ENDED);
        Ok(sent)
    }

    /// The next message to `to` (its sequence number on that link),
    /// recorded (`coord_send`, but for [`ENDED`]) and journaled.
    fn message(&mut self, to: String, transition: String, t: f64) -> CoordMessage {
        let seq = self.seq.entry(to.clone()).or_insert(0);
        *seq += 1;
        let m = CoordMessage { from: self.name.clone(), to, transition, seq: *seq, t };
        self.s.journal_entry(&Entry::CoordSend { t, to: m.to.clone(), transition: m.transition.clone(), seq: m.seq });
        if m.transition == ENDED {
            return m;
        }
        if m.transition.starts_with("coord.request.") {
            self.mutex.requests += 1;
        } else if m.transition.starts_with("coord.lend.") {
            self.mutex.grants += 1;
        } else if m.transition.starts_with("coord.return.")
            || self.tokens.iter().any(|(k, _)| k.holder == m.to && k.ends.contains(&m.transition))
        {
            self.mutex.returns += 1;
        }
        let kind = RecordKind::CoordSend { seq: m.seq, transition: m.transition.clone(), to: m.to.clone() };
        self.s.emit_record(Record::new(t, kind));
        m
    }

    /// The messages that the firings of `outs` require (and the requests
    /// for tokens they answer).
    fn messages_for(&mut self, outs: &[Output]) -> Result<Vec<CoordMessage>, String> {
        let mut sent = Vec::new();
        for o in outs {
            let Output::Fired { t, transition, .. } = o else { continue };
            let id = self.s.player.net().transitions()[transition.index()].id.to_string();
            for (k, asked) in &mut self.tokens {
                if k.grant == *transition {
                    *asked = asked.saturating_sub(1);
                } else if k.request == id {
                    *asked += 1;
                }
            }
            let Some(to) = self.sends.get(&id) else { continue };
            for to in to.clone() {
                sent.push(self.message(to, id.clone(), *t));
            }
        }
        Ok(sent)
    }

    /// Tells every peer that the mission has ended ([`ENDED`]), once.
    fn send_ended(&mut self, peers: &[String], t: f64) -> Result<(), String> {
        if self.ended_sent || peers.is_empty() {
            return Ok(());
        }
        self.ended_sent = true;
        self.s.journal_entry(&Entry::CoordEnded { t });
        let sent = peers.iter().map(|p| self.message(p.clone(), ENDED.into(), t)).collect();
        self.commit(&[], sent)?;
        Ok(())
    }

    /// The single-holder mutex protocol, on this vehicle's side: for each
    /// mutex held by another vehicle (in the order of their ids), the
    /// tokens that its calls which could start but for such tokens need
    /// (a call asks for the mutex of a larger id only once it has those of
    /// the smaller ones: no two vehicles each keep a token the other
    /// waits for) are asked for (events `coord.request.*`, one per token),
    /// and the tokens no such call needs are given back (`coord.return.*`).
    /// Returns the events to raise. Once the mission has ended, unused
    /// tokens are given back by a message alone (added to `sent`).
    fn arbitrate(&mut self, sent: &mut Vec<CoordMessage>) -> Result<Vec<String>, String> {
        if self.tokens.is_empty() || !self.s.player.is_started() {
            return Ok(Vec::new());
        }
        if self.s.player.outcome().is_some() {
            // The player takes no more events: a message alone returns
            // each unused token (nothing else can use it).
            let t = self.s.player.now();
            let mut tokens = self.ended_marking();
            let back: Vec<(String, String, u32)> = self
                .tokens
                .iter()
                .map(|(k, _)| (k.holder.clone(), k.ret.clone(), std::mem::take(&mut tokens.0[k.place.index()])))
                .collect();
            self.after_end = Some(tokens);
            for (to, ret, n) in back {
                for _ in 0..n {
                    sent.push(self.message(to.clone(), ret.clone(), t));
                }
            }
            return Ok(Vec::new());
        }
        if self.replaying {
            // The requests and returns are inputs of the journal.
            return Ok(Vec::new());
        }
        let net = self.s.player.net().clone();
        let m = self.s.player.marking().clone();
        let places: Vec<mcl_net::PlaceId> = self.tokens.iter().map(|(k, _)| k.place).collect();
        let mut events = Vec::new();
        for (i, (k, asked)) in self.tokens.iter_mut().enumerate() {
            let mut need = 0u32;
            for &(t, w) in &k.starts {
                // Enabled once this and the later borrowed places are served.
                let ready = is_enabled_with(&net, t, |p| match places.iter().position(|&q| q == p) {
                    Some(j) if j >= i => u32::MAX,
                    _ => m.get(p),
                });
                if ready {
                    need += w;
                }
            }
            let have = m.get(k.place);
            if have + *asked < need {
                // `asked` counts them when they fire (`messages_for`).
                for _ in 0..need - have - *asked {
                    events.push(k.request.clone());
                }
            } else if have > need {
                for _ in 0..have - need {
                    events.push(k.ret.clone());
                }
            }
        }
        Ok(events)
    }

    fn ended_marking(&self) -> Marking {
        self.after_end.clone().unwrap_or_else(|| self.s.player.marking().clone())
    }

    /// Once the mission has ended, its supervisor places still serve the
    /// others: the messages of the inbox whose receive transitions touch
    /// only supervisor places fire on the final marking (a holder grants
    /// and takes back its mutex), recorded as events and firings. None when
    /// none can.
    fn serve_ended(&mut self, t: f64) -> Option<Vec<Output>> {
        let net = self.s.player.net().clone();
        let mut tokens = self.ended_marking();
        let mut outs = Vec::new();
        loop {
            let mut kept = VecDeque::new();
            let before = outs.len();
            for m in std::mem::take(&mut self.inbox) {
                let event = m.event();
                let tr = net.event_transitions(&event).iter().copied().find(|&tr| {
                    is_enabled(&net, &tokens, tr)
                        && net
                            .post(tr)
                            .iter()
                            .chain(net.pre(tr))
                            .all(|&(p, _)| net.place(p).is_some_and(|x| x.id.starts_with("coord.")))
                });
                match tr {
                    Some(tr) => {
                        fire(&net, &mut tokens, tr).map_err(|e| e.to_string()).ok()?;
                        outs.push(Output::Event { t, event, transition: tr, call_site: None, activation: None });
                        outs.push(Output::Fired { t, transition: tr, call_site: None });
                    }
                    None => kept.push_back(m),
                }
            }
            self.inbox = kept;
            if outs.len() == before || self.inbox.is_empty() {
                break;
            }
        }
        self.after_end = Some(tokens);
        if outs.is_empty() {
            return None;
        }
        for o in &outs {
            self.s.emit(o);
        }
        Some(outs)
    }

    /// Takes `m`, from the transport at time `t`: journals it (synced)
    /// and acknowledges it, records it and keeps it in the inbox; an
    /// [`ENDED`] message is counted instead (not recorded). True for
    /// [`ENDED`].
    fn received(&mut self, m: CoordMessage, t: f64) -> Result<bool, String> {
        let t = t.max(self.s.player.now());
        if !self.replaying {
            self.s.journal_entry(&Entry::CoordReceive {
                t,
                from: m.from.clone(),
                transition: m.transition.clone(),
                seq: m.seq,
                sent_t: m.t,
            });
            self.s.sync()?;
            self.transport.delivered(&m);
        }
        if m.transition == ENDED {
            self.peers_ended += 1;
            return Ok(true);
        }
        let kind = RecordKind::CoordReceive {
            seq: m.seq,
            event: m.event(),
            transition: m.transition.clone(),
            from: m.from.clone(),
        };
        self.s.emit_record(Record::new(t, kind));
        self.inbox.push_back(m);
        Ok(false)
    }

    /// Records a line or connection that the transport refused.
    fn rejected(&mut self, why: String, t: f64) {
        self.s.emit_record(Record::new(t.max(self.s.player.now()), RecordKind::CoordReject { message: why }));
    }

    /// Rebuilds the vehicle from its journal: the player (inputs), the
    /// mock (the actions), the inbox (messages received, minus those
    /// delivered), the numbering of the messages sent and the messages
    /// themselves (derived from the firings, as when they were first sent:
    /// they are all sent again, and the receivers drop those they have),
    /// the peers that have ended. Records go to the trace as they did.
    fn replay(&mut self, entries: &[Entry], peers: &[String]) -> Result<Vec<CoordMessage>, String> {
        self.replaying = true;
        self.s.sink.replaying(true);
        let journal = self.s.journal.take();
        let r = self.replay_entries(entries, peers);
        self.s.journal = journal;
        self.s.sink.replaying(false);
        self.replaying = false;
        let inputs = r?;
        let resend = std::mem::take(&mut self.resend);
        let t = self.s.player.now();
        let r = Record::link(t, format!(
            "resumed from the journal: {inputs} inputs replayed, {} transitions fired, {} messages sent again, {} waiting",
            self.s.player.fired_count(),
            resend.len(),
            self.inbox.len()
        ));
        self.s.emit_record(r);
        for m in &resend {
            self.transport.send(m.clone())?;
        }
        Ok(resend.into_iter().filter(|m| m.transition != ENDED).collect())
    }

    fn replay_entries(&mut self, entries: &[Entry], peers: &[String]) -> Result<usize, String> {
        let mut replay = Replay::new(entries);
        let mut inputs = 0;
        while let Some(step) = replay.next(&mut self.s.player) {
            match step? {
                Step::Input(input, outs) => {
                    inputs += 1;
                    if let Some(m) = input.message() {
                        self.mock.take_delivered(&m);
                    }
                    if matches!(input, Input::Events(..)) {
                        self.taken(&outs);
                    }
                    for o in &outs {
                        self.s.emit(o);
                    }
                    self.replay_after(&outs)?;
                }
                Step::Other(Entry::CoordReceive { t, from, transition, seq, sent_t }) => {
                    let m = CoordMessage {
                        from: from.clone(),
                        to: self.name.clone(),
                        transition: transition.clone(),
                        seq: *seq,
                        t: *sent_t,
                    };
                    self.received(m, *t)?;
                }
                Step::Other(Entry::CoordServed { t }) => {
                    if let Some(outs) = self.serve_ended(*t) {
                        self.replay_after(&outs)?;
                    }
                }
                Step::Other(Entry::CoordEnded { t }) => self.send_ended(peers, *t)?,
                // The operator aborted: the mission's end is `aborted`.
                Step::Other(Entry::Operator { command: Command::Abort, .. }) => self.s.set_operator_aborted(),
                Step::Other(_) => {}
            }
        }
        Ok(inputs)
    }

    /// [`Live::after`] while replaying: the requests and returns of the
    /// mutex protocol are inputs of the journal, replayed in their turn.
    fn replay_after(&mut self, outs: &[Output]) -> Result<(), String> {
        let mut sent = self.messages_for(outs)?;
        self.arbitrate(&mut sent)?;
        self.commit(outs, sent)?;
        Ok(())
    }

    /// Removes from the inbox the messages whose events `outs` took.
    fn taken(&mut self, outs: &[Output]) {
        for o in outs {
            if let Output::Event { event, .. } = o {
                if let Some(k) = self.inbox.iter().position(|m| m.event() == *event) {
                    self.inbox.remove(k);
                }
            }
        }
    }

    /// Starts the player at `t`. Messages received before are delivered
    /// first: their receive transitions (which touch supervisor copies
    /// only) fire on the initial marking, so that the start's cascade
    /// already sees them (a call that another vehicle holds under a mutex
    /// stays held). Each is recorded as an `event`.
    fn start(&mut self, t: f64) -> Result<Vec<Output>, String> {
        if !self.inbox.is_empty() {
            let net = self.s.player.net().clone();
            let mut tokens = net.initial_marking();
            let mut kept = VecDeque::new();
            let mut delivered = Vec::new();
            for m in std::mem::take(&mut self.inbox) {
                let event = m.event();
                let enabled = net.event_transitions(&event).iter().copied().find(|&tr| {
                    !self.sends.contains_key(net.transitions()[tr.index()].id.as_str())
                        && is_enabled(&net, &tokens, tr)
                        && net
                            .post(tr)
                            .iter()
                            .chain(net.pre(tr))
                            .all(|&(p, _)| net.place(p).is_some_and(|x| x.id.starts_with("coord.")))
                });
                match enabled {
                    Some(tr) => {
                        fire(&net, &mut tokens, tr).map_err(|e| e.to_string())?;
                        delivered.push((event, net.transitions()[tr.index()].id.clone()));
                    }
                    None => kept.push_back(m),
                }
            }
            self.inbox = kept;
            if !delivered.is_empty() {
                let mut b = net.to_builder();
                for p in net.place_ids() {
                    if let Some(place) = b.place_mut(p) {
                        place.initial = tokens.get(p);
                    }
                }
                let net = b.build().map_err(|e| format!("`{}`: {e}", self.name))?;
                self.s.player = Player::new(Arc::new(net), self.opts.clone());
                for (event, transition) in delivered {
                    let kind = RecordKind::Event {
                        event,
                        transition: transition.to_string(),
                        call: Default::default(),
                        activation: None,
                        ends: None,
                    };
                    self.s.emit_record(Record::new(t, kind));
                }
            }
        }
        self.s.step(Input::Start(t))
    }

    /// Delivers at time `t`, all at once ([`Player::on_events`]), the
    /// messages of the inbox whose receive transitions can fire; the others
    /// stay (journaled as one input, [`Input::Events`]). None when none can.
    fn deliver(&mut self, t: f64) -> Result<Option<Vec<Output>>, String> {
        if !self.s.player.is_started() || self.inbox.is_empty() {
            return Ok(None);
        }
        if self.s.player.outcome().is_some() {
            let t = t.max(self.s.player.now());
            let Some(outs) = self.serve_ended(t) else { return Ok(None) };
            self.s.journal_entry(&Entry::CoordServed { t });
            return Ok(Some(outs));
        }
        let awaited = self.s.player.awaited_events();
        if !self.inbox.iter().any(|m| awaited.binary_search(&m.event()).is_ok()) {
            return Ok(None);
        }
        let events: Vec<String> = self.inbox.iter().map(CoordMessage::event).collect();
        // Journaled with the messages it sends (`after`).
        let outs = self.s.step(Input::Events(t.max(self.s.player.now()), events))?;
        self.taken(&outs);
        Ok(Some(outs))
    }

    fn idle(&self) -> bool {
        self.end.is_some() || (self.s.player.next_deadline().is_none() && self.mock.next_deadline().is_none())
    }

    fn stuck(&mut self, t: f64) -> End {
        let mut awaited = self.s.player.awaited_events();
        awaited.retain(|e| !e.starts_with("coord."));
        let waiting: Vec<&String> = awaited.iter().filter(|e| e.contains('/')).collect();
        self.s.end_by_driver(
            t,
            "stuck",
            format!(
                "nothing more can happen in any vehicle and no message is in flight; `{}` waits for {}{}",
                self.name,
                if awaited.is_empty() { "nothing".to_string() } else { awaited.join(", ") },
                if waiting.is_empty() {
                    String::new()
                } else {
                    " (events `mission/transition` are coordination messages)".into()
                }
            ),
        );
        End::Quiescent { awaited }
    }
}

fn live(vehicles: Vec<Vehicle>, handles: &mut [SharedHandle]) -> Vec<Live<'_>> {
    vehicles
        .into_iter()
        .zip(handles.iter_mut())
        .map(|(v, h)| Live {
            name: v.name,
            s: {
                let mut s = Session::new(v.player, v.tracer, h);
                s.journal = v.journal;
                s.crash_after = v.crash_after;
                s.defer_sync = true;
                s
            },
            opts: v.opts,
            mock: v.mock,
            transport: v.transport,
            sends: v.sends,
            inbox: VecDeque::new(),
            seq: HashMap::new(),
            end: None,
            tokens: v.tokens.into_iter().map(|k| (k, 0)).collect(),
            mutex: MutexMessages::default(),
            after_end: None,
            replaying: false,
            resend: Vec::new(),
            ended_sent: false,
            peers_ended: 0,
            start_at: v.start_at,
            delays: v.delays,
        })
        .collect()
}

/// The `mission` of the records that concern every mission of a run.
pub const ALL_MISSIONS: &str = "*";

fn summary(sink: &SharedSink, t: f64, end: &MultiEnd) {
    let value = if end.mutex.total() > 0 { serde_json::to_value(end.mutex).ok() } else { None };
    let kind = RecordKind::CoordSummary { value, result: end.result().to_string(), messages: end.messages };
    let r = Record { mission: Some(ALL_MISSIONS.to_string()), ..Record::new(t, kind) };
    if let Ok(mut s) = sink.lock() {
        s.record(&r);
    }
}

fn finish(vs: &[Live<'_>], messages: u64) -> MultiEnd {
    MultiEnd {
        ends: vs
            .iter()
            .map(|v| {
                let end = v.end.clone().unwrap_or(End::Outcome(v.s.player.outcome().unwrap_or(Outcome::Stuck)));
                let t = end.driver_time().unwrap_or(v.s.player.now());
                (v.name.clone(), end, t)
            })
            .collect(),
        fired: vs.iter().map(|v| v.s.player.fired_count()).collect(),
        messages,
        mutex: vs.iter().fold(MutexMessages::default(), |mut a, v| {
            a.add(v.mutex);
            a
        }),
    }
}

/// Runs `vehicles` in virtual time (see the [module documentation](self)),
/// writing records to `sink`. Runs inside a tokio runtime (the transport's).
/// The loop is [`virtual_loop::run`].
pub async fn run_virtual(vehicles: Vec<Vehicle>, sink: SharedSink, limits: Limits) -> Result<MultiEnd, String> {
    run_virtual_with_link(vehicles, sink, limits, None, None).await
}

/// [`run_virtual`], each input taken once `pace` reaches its time
/// ([`virtual_loop::run_paced`]: `mcl run --sim --speed X` with several
/// vehicles): the same run, at the speed of the clock.
pub async fn run_virtual_paced(
    vehicles: Vec<Vehicle>,
    sink: SharedSink,
    limits: Limits,
    pace: Option<Clock>,
) -> Result<MultiEnd, String> {
    run_virtual_with_link(vehicles, sink, limits, None, pace).await
}

/// [`run_virtual_paced`] with every message carried by a modelled acoustic
/// link when `link` is given ([`crate::acoustic`]): messages are delayed,
/// lost and sent again, delivered in order once; the link's records
/// (`link_send`, `link_lost`, `link_deliver`) and a `link` summary go to the
/// trace.
pub async fn run_virtual_with_link(
    vehicles: Vec<Vehicle>,
    sink: SharedSink,
    limits: Limits,
    link: Option<AcousticLink>,
    pace: Option<Clock>,
) -> Result<MultiEnd, String> {
    let channel = match link {
        Some(link) => {
            let nets: Vec<(&str, &Net)> = vehicles.iter().map(|v| (v.name.as_str(), &**v.player.net())).collect();
            let book = Codebook::of_nets(nets, mcl_net::wire::DEFAULT_SEQ_BITS).map_err(|e| e.to_string())?;
            Some(Channel::new(link, book, sink.clone()))
        }
        None => None,
    };
    let mut vehicles = vehicles;
    // The operator's commands, each receiver with its vehicle.
    let (operated, commands): (Vec<usize>, Vec<operator::Receiver>) =
        vehicles.iter_mut().enumerate().filter_map(|(i, v)| v.operator.take().map(|c| (i, c))).unzip();
    let mut handles: Vec<SharedHandle> = vehicles.iter().map(|_| SharedHandle(sink.clone())).collect();
    let vs = live(vehicles, &mut handles);
    let index: HashMap<String, usize> = vs.iter().enumerate().map(|(i, v)| (v.name.clone(), i)).collect();
    let mut fleet = Fleet { vs, index, work: VecDeque::new(), sent: 0, now: 0.0, channel, held: Vec::new(), operated };
    // Vehicles start one after the other at 0, each after the messages of
    // the previous ones' first firings; those given a later start time
    // start then (`Due::Start`).
    fleet.exchange_messages().await?;
    for i in 0..fleet.vs.len() {
        if fleet.vs[i].start_at > 0.0 {
            continue;
        }
        let outs = fleet.vs[i].start(0.0)?;
        fleet.work.push_back((i, outs));
        fleet.exchange_messages().await?;
    }
    let stop = virtual_loop::run_operated(&mut fleet, &limits, pace, commands).await?;
    let running = fleet.vs.iter_mut().filter(|v| v.end.is_none());
    match stop {
        Stop::Over => {}
        Stop::Quiescent => {
            for v in running {
                let t = v.s.player.now();
                v.end = Some(v.stuck(t));
            }
        }
        Stop::TimeLimit(limit) => {
            for v in running {
                v.s.end_by_driver(limit, "time_limit", limits.passed(limit));
                v.end = Some(End::TimeLimit(limit));
            }
            fleet.now = fleet.now.max(limit);
        }
        Stop::ZeroTimeLoop(t) => {
            for v in running {
                v.s.end_by_driver(t, "stuck", virtual_loop::zero_time_message(t));
                v.end = Some(End::ZeroTimeLoop(t));
            }
        }
    }
    let end = finish(&fleet.vs, fleet.sent);
    if let Some(c) = &fleet.channel {
        let s = c.stats();
        let r = Record {
            mission: Some(ALL_MISSIONS.to_string()),
            ..Record::link(
                fleet.now,
                format!(
                    "acoustic link: {} messages, {} frames ({} retransmissions, {} lost), {} bytes on the wire; the messages as JSON: {} bytes",
                    s.messages, s.frames, s.retransmissions, s.lost, s.bytes, s.json_bytes
                ),
            )
        };
        if let Ok(mut k) = sink.lock() {
            k.record(&r);
        }
    }
    summary(&sink, fleet.now, &end);
    Ok(end)
}

/// The vehicles of a virtual-time run, for the virtual-time loop: the
/// inputs whose consequences are not yet settled (`work`), the messages
/// sent, the time.
struct Fleet<'a> {
    vs: Vec<Live<'a>>,
    index: HashMap<String, usize>,
    work: VecDeque<(usize, Vec<Output>)>,
    sent: u64,
    now: f64,
    /// The modelled link, when messages travel over one.
    channel: Option<Channel>,
    /// Without one, the messages delivered late ([`Vehicle::delaying`]),
    /// in the order sent, each with its delivery time.
    held: Vec<(f64, CoordMessage)>,
    /// The vehicle of each operator's receiver ([`Vehicle::with_operator`]).
    operated: Vec<usize>,
}

/// The [`Discrete`] source of the modelled link's events.
const LINK: (usize, Due) = (usize::MAX, Due::Link);

/// The [`Discrete`] source of the messages delivered late.
const HELD: (usize, Due) = (usize::MAX, Due::Held);

impl Fleet<'_> {
    /// Carries the consequences of the last inputs, messages included, at
    /// `now`: each message is awaited until its receiver has it; then one
    /// vehicle takes its messages, and what it does in reaction reaches the
    /// others before the next one does.
    async fn exchange_messages(&mut self) -> Result<(), String> {
        let now = self.now;
        while let Some((i, outs)) = self.work.pop_front() {
            let msgs = self.vs[i].after(&outs)?;
            self.sent += msgs.len() as u64;
            for m in msgs {
                let j = *self
                    .index
                    .get(&m.to)
                    .ok_or_else(|| format!("`{}` sends to an unknown mission `{}`", m.from, m.to))?;
                loop {
                    let got = tokio::time::timeout(DELIVERY_TIMEOUT, self.vs[j].transport.recv())
                        .await
                        .map_err(|_| {
                            format!("a message from `{}` did not reach `{}` within {DELIVERY_TIMEOUT:?}", m.from, m.to)
                        })?
                        .ok_or_else(|| format!("the transport of `{}` closed", m.to))?;
                    match got {
                        Incoming::Message(got) => {
                            match &mut self.channel {
                                Some(c) => c.offer(now, got)?,
                                None => match self.held_until(i, &got) {
                                    Some(until) if until > now => self.held.push((until, got)),
                                    _ => {
                                        self.vs[j].received(got, now.max(m.t))?;
                                    }
                                },
                            }
                            break;
                        }
                        Incoming::Rejected(why) => self.vs[j].rejected(why, now),
                    }
                }
            }
            if self.work.is_empty() {
                for (j, v) in self.vs.iter_mut().enumerate() {
                    if let Some(outs) = v.deliver(now)? {
                        self.work.push_back((j, outs));
                        break;
                    }
                }
            }
        }
        Ok(())
    }

    /// When the message `m` that vehicle `i` sent is delivered, if late:
    /// the time its sender's delays give it, and not before a message
    /// still held on the same link (messages arrive in order).
    fn held_until(&self, i: usize, m: &CoordMessage) -> Option<f64> {
        let own = self.vs[i].delays.iter().filter(|(to, seq, _)| *to == m.to && *seq == m.seq).map(|d| d.2);
        let before = self.held.iter().filter(|(_, h)| h.from == m.from && h.to == m.to).map(|h| h.0);
        own.chain(before).reduce(f64::max)
    }
}

/// What is due for a vehicle of a virtual-time run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Due {
    /// Its player's timers.
    Timer,
    /// Its vehicle's messages.
    Vehicle,
    /// Its mission's start.
    Start,
    /// The modelled link's deliveries ([`LINK`], not a vehicle's).
    Link,
    /// The deliveries of messages held late ([`HELD`], not a vehicle's).
    Held,
}

impl Discrete for Fleet<'_> {
    /// The vehicle, and what is due for it.
    type Source = (usize, Due);

    fn is_over(&mut self) -> bool {
        for v in self.vs.iter_mut().filter(|v| v.end.is_none()) {
            if let Some(o) = v.s.player.outcome() {
                v.end = Some(End::Outcome(o));
            }
        }
        self.vs.iter().all(|v| v.end.is_some())
    }

    fn deadlines(&self, out: &mut Vec<(f64, (usize, Due))>) {
        for (i, v) in self.vs.iter().enumerate().filter(|(_, v)| v.end.is_none()) {
            if !v.s.player.is_started() {
                out.push((v.start_at, (i, Due::Start)));
                continue;
            }
            out.extend(v.s.player.next_deadline().map(|t| (t, (i, Due::Timer))));
            out.extend(v.mock.next_deadline().map(|t| (t, (i, Due::Vehicle))));
        }
        out.extend(self.channel.as_ref().and_then(Channel::next_deadline).map(|t| (t, LINK)));
        out.extend(self.held.iter().map(|h| h.0).reduce(f64::min).map(|t| (t, HELD)));
    }

    async fn operator(&mut self, t: f64, who: usize, c: Command) -> Result<(), String> {
        let Some(i) = self.operated.get(who).copied() else { return Ok(()) };
        self.now = self.now.max(t);
        let v = &mut self.vs[i];
        if v.end.is_some() || !v.s.player.is_started() {
            let why = if v.end.is_some() { "has ended" } else { "has not started" };
            v.s.warn(t, format!("operator: {} ignored: the mission {why}", c.name()));
            return Ok(());
        }
        let outs = v.s.operator_input(t, c)?;
        self.work.push_back((i, outs));
        self.exchange_messages().await
    }

    async fn step(&mut self, t: f64, (i, due): (usize, Due)) -> Result<(), String> {
        self.now = self.now.max(t);
        if due == Due::Link || due == Due::Held {
            let arrived = match &mut self.channel {
                Some(c) if due == Due::Link => c.step(t)?,
                Some(_) => Vec::new(),
                None => {
                    let (due_now, later): (Vec<_>, Vec<_>) = self.held.drain(..).partition(|h| h.0 <= t);
                    self.held = later;
                    due_now.into_iter().map(|h| h.1).collect()
                }
            };
            for m in arrived {
                let j = *self.index.get(&m.to).ok_or_else(|| format!("a message for an unknown mission `{}`", m.to))?;
                self.vs[j].received(m, t)?;
            }
            for (j, v) in self.vs.iter_mut().enumerate() {
                if let Some(outs) = v.deliver(t)? {
                    self.work.push_back((j, outs));
                    break;
                }
            }
            return self.exchange_messages().await;
        }
        let v = &mut self.vs[i];
        if due == Due::Start {
            let outs = v.start(t)?;
            self.work.push_back((i, outs));
        } else if due == Due::Timer {
            let outs = v.s.step(Input::Timer(t))?;
            self.work.push_back((i, outs));
        } else if let Some((tm, m)) = v.mock.pop_due(t) {
            if let Some(input) = perception_or_event(tm, m) {
                let outs = v.s.step(input)?;
                self.work.push_back((i, outs));
            }
        } else {
            // A simulated vehicle moved without a message: its poses now,
            // in time order with the other records.
            drain_poses(&mut v.s, &mut *v.mock);
        }
        self.exchange_messages().await
    }
}

/// Shared state of the real-time run: which vehicles are idle (or ended), and
/// per vehicle the messages sent to it and those it took from the transport.
struct Global {
    idle: Vec<bool>,
    sent_to: Vec<u64>,
    received: Vec<u64>,
    stop: tokio::sync::watch::Sender<bool>,
    /// Vehicles in other processes, and how many of them said they ended.
    peers: usize,
    peers_ended: usize,
    /// Messages sent to vehicles in other processes.
    sent_remote: u64,
}

impl Global {
    /// Records whether vehicle `i` is idle, and stops the run when every
    /// vehicle is (an ended one is) and no message is in flight.
    fn set_idle(&mut self, i: usize, idle: bool) {
        self.idle[i] = idle;
        let quiet = (0..self.idle.len()).all(|j| self.idle[j] && self.sent_to[j] == self.received[j])
            && self.peers_ended >= self.peers;
        if quiet {
            let _ = self.stop.send(true);
        }
    }
}

fn count_sent(g: &mut Global, index: &HashMap<String, usize>, msgs: &[CoordMessage]) {
    for m in msgs {
        match index.get(&m.to) {
            Some(&j) => g.sent_to[j] += 1,
            None => g.sent_remote += 1,
        }
    }
}

fn lock(g: &Mutex<Global>) -> Result<std::sync::MutexGuard<'_, Global>, String> {
    g.lock().map_err(|_| "a vehicle task panicked".to_string())
}

/// Runs `vehicles` in real time with `clock` (see the [module
/// documentation](self)), one task per vehicle on the current tokio runtime.
pub async fn run_real_time(
    vehicles: Vec<Vehicle>,
    sink: SharedSink,
    clock: Clock,
    limits: Limits,
) -> Result<MultiEnd, String> {
    run_real_time_with_peers(vehicles, sink, clock, limits, &[]).await
}

/// The transition of the message a vehicle sends to the vehicles of other
/// processes when its mission has ended (not a firing: no receive
/// transition waits for it).
pub const ENDED: &str = "coord.ended";

/// [`run_real_time`] for some vehicles of a coordinated run, the missions
/// `peers` running in other processes (`mcl run --vehicle NAME
/// --coord-peer NAME=ADDR`): messages to them go over the transport like
/// the others; each vehicle tells every peer when its mission has ended
/// (message [`ENDED`]), and the run ends only once every peer has (a
/// vehicle still serves its supervisor places after its own end: a holder
/// still lends its mutex), or at the time limit.
pub async fn run_real_time_with_peers(
    vehicles: Vec<Vehicle>,
    sink: SharedSink,
    clock: Clock,
    limits: Limits,
    peers: &[String],
) -> Result<MultiEnd, String> {
    let peers: Arc<Vec<String>> = Arc::new(peers.to_vec());
    let n = vehicles.len();
    let (stop_tx, stop_rx) = tokio::sync::watch::channel(false);
    let index: Arc<HashMap<String, usize>> =
        Arc::new(vehicles.iter().enumerate().map(|(i, v)| (v.name.clone(), i)).collect());
    let global = Arc::new(Mutex::new(Global {
        idle: vec![false; n],
        sent_to: vec![0; n],
        received: vec![0; n],
        stop: stop_tx,
        peers: peers.len() * n,
        peers_ended: 0,
        sent_remote: 0,
    }));
    let mut tasks = Vec::new();
    for (i, v) in vehicles.into_iter().enumerate() {
        let (sink, global, mut stop, index) = (sink.clone(), global.clone(), stop_rx.clone(), index.clone());
        let peers = peers.clone();
        let on_error = global.clone();
        let mut v = v;
        let resume = v.resume.take();
        let mut commands = v.operator.take();
        tasks.push(tokio::spawn(async move {
            let r = async move {
                let mut handle = [SharedHandle(sink)];
                let mut vs = live(vec![v], &mut handle);
                let v = &mut vs[0];
                let mut outs = Vec::new();
                if let Some(entries) = resume {
                    let resent = v.replay(&entries, &peers)?;
                    let mut g = lock(&global)?;
                    g.peers_ended += v.peers_ended;
                    count_sent(&mut g, &index, &resent);
                }
                if !v.s.player.is_started() {
                    outs = v.start(clock.now())?;
                }
                // The operator's pause: this vehicle's clock stops at that
                // instant, and the outputs of commands taken meanwhile
                // (an answer) wait for `resume` (or the mission's end).
                let mut clock = clock;
                let mut paused: Option<f64> = None;
                let mut held: Vec<Output> = Vec::new();
                let result: Result<End, String> = loop {
                    if paused.is_some() && v.s.player.outcome().is_none() {
                        held.append(&mut outs);
                    } else if !held.is_empty() {
                        held.append(&mut outs);
                        outs = std::mem::take(&mut held);
                    }
                    let msgs = v.after(&outs)?;
                    count_sent(&mut *lock(&global)?, &index, &msgs);
                    outs = Vec::new();
                    if paused.is_none() {
                        if let Some(o) = v.deliver(clock.now())? {
                            outs = o;
                            continue;
                        }
                    }
                    if let Some(o) = v.s.player.outcome() {
                        break Ok(End::Outcome(o));
                    }
                    // An aborted mission is over once nothing more happens in
                    // it (its peers in other processes cannot tell: they wait
                    // for its `ENDED`); it is recorded `aborted`.
                    if v.s.operator_aborted() && v.idle() && paused.is_none() {
                        let t = clock.now().max(v.s.player.now());
                        break Ok(v.stuck(t));
                    }
                    lock(&global)?.set_idle(i, v.idle() && paused.is_none());
                    let (tp, tm) = (v.s.player.next_deadline(), v.mock.next_deadline());
                    let wake = [tp, tm, limits.time_limit].into_iter().flatten().reduce(f64::min);
                    let until = wake.map(|w| clock.instant_at(w));
                    let sleep = async move {
                        match until {
                            Some(u) => tokio::time::sleep_until(u).await,
                            None => std::future::pending::<()>().await,
                        }
                    };
                    tokio::select! {
                        c = async {
                            match &mut commands {
                                Some(c) => c.recv().await,
                                None => std::future::pending().await,
                            }
                        } => match c {
                            // The operator's side is gone: no more commands.
                            None => commands = None,
                            Some(c) => {
                                let now = paused.unwrap_or_else(|| clock.now()).max(v.s.player.now());
                                let ignored = match &c {
                                    Command::Pause => paused.is_some(),
                                    Command::Resume => paused.is_none(),
                                    Command::Abort | Command::Answer { .. } => false,
                                };
                                if ignored {
                                    let state = if paused.is_some() { "paused" } else { "running" };
                                    v.s.warn(now, format!("operator: {} ignored (`{}` is {state})", c.name(), v.name));
                                } else {
                                    match &c {
                                        Command::Pause => paused = Some(now),
                                        // An abort ends the pause: nothing is left to resume,
                                        // and the run may then end.
                                        Command::Resume | Command::Abort => {
                                            if let Some(at) = paused.take() {
                                                clock = Clock::new(clock.speed(), at);
                                            }
                                        }
                                        Command::Answer { .. } => {}
                                    }
                                    outs = v.s.operator_input(now, c)?;
                                }
                            }
                        },
                        m = v.transport.recv(), if paused.is_none() => match m {
                            Some(Incoming::Message(m)) => {
                                let local = index.contains_key(&m.from);
                                let ended = v.received(m, clock.now())?;
                                let mut g = lock(&global)?;
                                if ended && !local {
                                    g.peers_ended += 1;
                                } else if local {
                                    g.received[i] += 1;
                                }
                                g.set_idle(i, false);
                            }
                            Some(Incoming::Rejected(why)) => v.rejected(why, clock.now()),
                            None => break Err(format!("the coordination transport of `{}` closed", v.name)),
                        },
                        _ = sleep, if paused.is_none() => {
                            let now = clock.now().max(v.s.player.now());
                            if tp.is_some_and(|d| d <= now) {
                                outs = v.s.step(Input::Timer(now))?;
                            } else if tm.is_some_and(|d| d <= now) {
                                // One message at a time: the mock learns the
                                // actions it causes before it sends the next.
                                if let Some((_, m)) = v.mock.pop_due(now) {
                                    if let Some(input) = perception_or_event(now, m) {
                                        outs = v.s.step(input)?;
                                    }
                                }
                            } else if let Some(limit) = limits.time_limit.filter(|&l| l <= now) {
                                v.s.end_by_driver(limit, "time_limit", limits.passed(limit));
                                break Ok(End::TimeLimit(limit));
                            }
                        }
                        _ = stop.wait_for(|&s| s) => {
                            let t = clock.now();
                            break Ok(v.stuck(t));
                        }
                    }
                };
                v.end = Some(result?);
                {
                    // Messages kept in the inbox: a holder still lends its mutex.
                    let msgs = match v.deliver(clock.now())? {
                        Some(o) => v.after(&o)?,
                        None => Vec::new(),
                    };
                    // Tell the vehicles of other processes.
                    let t = v.s.player.now();
                    v.send_ended(&peers, t)?;
                    let mut g = lock(&global)?;
                    count_sent(&mut g, &index, &msgs);
                    g.set_idle(i, true);
                }
                // Keep taking messages (recorded; the mission has ended)
                // until every vehicle is done and none is in flight.
                loop {
                    tokio::select! {
                        m = v.transport.recv() => match m {
                            Some(Incoming::Message(m)) => {
                                let local = index.contains_key(&m.from);
                                let ended = v.received(m, clock.now())?;
                                // A holder still lends its mutex.
                                let msgs = match v.deliver(clock.now())? {
                                    Some(o) => v.after(&o)?,
                                    None => Vec::new(),
                                };
                                let mut g = lock(&global)?;
                                count_sent(&mut g, &index, &msgs);
                                if ended && !local {
                                    g.peers_ended += 1;
                                } else if local {
                                    g.received[i] += 1;
                                }
                                g.set_idle(i, true);
                            }
                            Some(Incoming::Rejected(why)) => v.rejected(why, clock.now()),
                            None => break,
                        },
                        _ = stop.wait_for(|&s| s) => break,
                    }
                }
                // Before leaving, let the peers acknowledge what was sent to
                // them (a peer that restarts needs it), for a while.
                let give_up = tokio::time::Instant::now() + FLUSH_TIMEOUT;
                while v.transport.unacknowledged() > 0 && tokio::time::Instant::now() < give_up {
                    tokio::select! {
                        m = v.transport.recv() => match m {
                            Some(Incoming::Message(m)) => {
                                v.received(m, clock.now())?;
                            }
                            Some(Incoming::Rejected(why)) => v.rejected(why, clock.now()),
                            None => break,
                        },
                        _ = tokio::time::sleep(Duration::from_millis(20)) => {}
                    }
                }
                // Let the last acknowledgements of this process leave.
                tokio::time::sleep(Duration::from_millis(20)).await;
                // The transport lives until every vehicle has ended: others may
                // still send to this one.
                let end = finish(&vs, 0);
                let transport = vs.pop().map(|v| v.transport);
                Ok::<_, String>((end, transport))
            }
            .await;
            if r.is_err() {
                // Stop the others: they may wait for this one.
                if let Ok(g) = on_error.lock() {
                    let _ = g.stop.send(true);
                }
            }
            r
        }));
    }
    let mut ends = Vec::new();
    let mut fired = Vec::new();
    let mut mutex = MutexMessages::default();
    let mut transports = Vec::new();
    let mut error = None;
    for t in tasks {
        match t.await.map_err(|e| format!("a vehicle task failed: {e}")).and_then(|r| r) {
            Ok((e, tr)) => {
                ends.extend(e.ends);
                fired.extend(e.fired);
                mutex.add(e.mutex);
                transports.push(tr);
            }
            Err(e) => {
                error.get_or_insert(e);
            }
        }
    }
    drop(transports);
    if let Some(e) = error {
        return Err(e);
    }
    let messages = global.lock().map(|g| g.sent_to.iter().sum::<u64>() + g.sent_remote).unwrap_or_default();
    let end = MultiEnd { ends, messages, fired, mutex };
    let last = end.ends.iter().map(|(_, _, t)| *t).fold(0.0, f64::max);
    summary(&sink, last, &end);
    Ok(end)
}

/// The scenario of `mission` from a scenario file's text: the file itself,
/// or, when it has `[missions.NAME]` tables, its top level merged with the
/// table of that mission (tables merged key by key, the mission's values
/// winning; arrays such as `events` appended). Errors in a merged scenario
/// name the mission's table; errors in a file without `missions` keep their
/// line and column.
pub fn scenario_for(text: &str, origin: &str, mission: &str) -> Result<crate::scenario::Scenario, String> {
    let mut table: toml::Table = match toml::from_str(text) {
        Ok(t) => t,
        // The scenario parser gives the better message (line and column).
        Err(_) => return crate::scenario::Scenario::from_toml(text, origin),
    };
    let Some(missions) = table.remove("missions") else {
        return crate::scenario::Scenario::from_toml(text, origin);
    };
    let toml::Value::Table(mut missions) = missions else {
        return Err(format!("{origin}: `missions` must be a table of `[missions.NAME]` tables"));
    };
    if let Some(own) = missions.remove(mission) {
        let toml::Value::Table(own) = own else {
            return Err(format!("{origin}: `missions.{mission}` must be a table"));
        };
        merge(&mut table, own);
    }
    let merged = toml::to_string(&table).map_err(|e| format!("{origin}: {e}"))?;
    crate::scenario::Scenario::from_toml(&merged, &format!("{origin} (merged for mission `{mission}`)"))
}

/// The `[missions.NAME]` tables of a scenario text (empty when it has none
/// or does not parse).
pub fn scenario_missions(text: &str) -> Vec<String> {
    match toml::from_str::<toml::Table>(text).ok().and_then(|mut t| t.remove("missions")) {
        Some(toml::Value::Table(m)) => m.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

fn merge(base: &mut toml::Table, over: toml::Table) {
    for (k, v) in over {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (Some(toml::Value::Array(b)), toml::Value::Array(o)) => b.extend(o),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_mission_scenario_sections() {
        let text = r#"
default_duration = 2
[tasks.Goto]
delay = 10
[[events]]
at = 1
event = "a"
[missions.asc.tasks.Goto]
outcome = "fail"
[[missions.asc.events]]
at = 2
event = "b"
"#;
        let asc = scenario_for(text, "s.toml", "asc").unwrap();
        let auv = scenario_for(text, "s.toml", "auv").unwrap();
        assert_eq!(asc.default_duration, Some(2.0));
        assert_eq!(asc.events.len(), 2);
        assert_eq!(auv.events.len(), 1);
        assert_eq!(asc.tasks["Goto"].base().outcome, Some(crate::scenario::OutcomeRule::Fail));
        assert_eq!(auv.tasks["Goto"].base().outcome, None);
        assert_eq!(scenario_missions(text), ["asc"]);
        // Without sections, errors keep their position.
        let e = scenario_for("[tasks.Goto]\ndelai = 3\n", "s.toml", "auv").unwrap_err();
        assert!(e.starts_with("s.toml:2:"), "{e}");
        let e = scenario_for("[missions.asc.tasks.Goto]\ndelai = 3\n", "s.toml", "asc").unwrap_err();
        assert!(e.contains("mission `asc`") && e.contains("delai"), "{e}");
    }
}
