//! The AAC protocol over TCP (`docs/aac-protocol.md`, module [`protocol`]).
//!
//! * Player side: [`connect`] returns a [`Link`] backed by a background task
//!   that connects, shakes hands, forwards actions, keeps every action until
//!   the AAC acknowledges it and re-sends it after a reconnection, reconnects
//!   with capped exponential backoff (reporting [`Inbound::Disconnected`] and
//!   [`Inbound::Connected`]), drops re-sent events and sends heartbeats.
//! * AAC side: [`serve`] / [`Server`] accept players and hand one
//!   [`AacEnd`] per *session* (one run of one mission) to a handler; a
//!   session outlives its connections: actions are executed once per `seq`,
//!   events are numbered and re-sent to a player that reconnects.
//! * [`serve_vehicle`] runs a sans-IO [`Vehicle`] (the mock vehicle) in real
//!   time behind the protocol, optionally persisting what it executed in a
//!   state file so that a restarted process neither forgets nor repeats.
//!
//! Every task must run inside a tokio runtime.
//!
//! [`protocol`]: crate::protocol

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::io;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};
use tokio::io::{AsyncWriteExt, BufReader};
use tokio::net::tcp::OwnedWriteHalf;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, Notify};
use tokio::task::JoinHandle;
use tokio::time::{sleep, sleep_until, timeout, timeout_at, Instant};

use crate::link::{pair, AacEnd, Action, Delivered, Inbound, Link};
use crate::protocol::{
    encode, parse, token_matches, truncate, ActionMsg, ErrorCode, EventMsg, Hello, Line, LineReader, Message,
    PerceptionMsg, Ping, Welcome, DEFAULT_PING_INTERVAL, DEFAULT_TIMEOUT, MAX_LINE, VERSION,
};

/// How much a side writes on standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// Nothing.
    #[default]
    Off,
    /// Connections, refusals, errors, duplicates, executed actions.
    Info,
    /// Also every message sent and received.
    Messages,
}

fn log(level: LogLevel, need: LogLevel, who: &str, msg: std::fmt::Arguments<'_>) {
    if level >= need && level != LogLevel::Off {
        eprintln!("[{:>10.3}] {who}: {msg}", unix_now() % 100_000.0);
    }
}

fn unix_now() -> f64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}

/// A fresh identifier (run ids, session ids): time, process and a counter.
pub fn new_id() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    format!("{:x}-{:x}-{:x}", nanos, std::process::id(), COUNTER.fetch_add(1, Ordering::Relaxed))
}

// ---------------------------------------------------------------------------
// Player side
// ---------------------------------------------------------------------------

/// Options of [`connect`].
#[derive(Clone, Debug)]
pub struct ConnectOptions {
    /// Shared secret sent in `hello`.
    pub token: Option<String>,
    /// Mission name sent in `hello`.
    pub mission: String,
    /// Run id: `None` draws a fresh one, so that each [`connect`] is a new
    /// session on the AAC (sequence numbers from scratch). A player resumed
    /// from a journal passes the run id of the interrupted run.
    pub run: Option<String>,
    /// Player software sent in `hello`.
    pub player: String,
    /// The player says itself which events it has handled (once it has
    /// journaled them): `ping` and `hello` then confirm what this handle
    /// holds, not what the link received, so that the AAC keeps what a
    /// crash of the player would lose. A handle that names a session at
    /// connect resumes an interrupted run (same `run`): the first `hello`
    /// names that session and its last event, and the AAC re-sends the
    /// events after it. `None`: the link confirms what it received.
    pub delivered: Option<Delivered>,
    /// When the AAC welcomes the run in another session than the one it
    /// knew (the AAC lost its memory), drop the actions not acknowledged
    /// instead of sending them again: the player re-establishes what it
    /// has running ([`Inbound::Session`]). `false`: they are sent again.
    pub reestablish: bool,
    /// Interval between two pings.
    pub ping_interval: Duration,
    /// Silence (and connect / write time) after which the AAC is considered gone.
    pub timeout: Duration,
    /// First delay before reconnecting; doubled after each failure…
    pub backoff_min: Duration,
    /// …up to this cap.
    pub backoff_max: Duration,
    /// Once the player has dropped its action sender, how long to keep
    /// trying to get the last actions acknowledged before giving up.
    pub linger: Duration,
    /// Longest accepted line.
    pub max_line: usize,
    /// Logging on standard error.
    pub log: LogLevel,
}

impl Default for ConnectOptions {
    fn default() -> Self {
        ConnectOptions {
            token: None,
            mission: "mission".into(),
            run: None,
            player: concat!("mcl/", env!("CARGO_PKG_VERSION")).into(),
            delivered: None,
            reestablish: false,
            ping_interval: DEFAULT_PING_INTERVAL,
            timeout: DEFAULT_TIMEOUT,
            backoff_min: Duration::from_millis(100),
            backoff_max: Duration::from_secs(5),
            linger: Duration::from_secs(10),
            max_line: MAX_LINE,
            log: LogLevel::Off,
        }
    }
}

/// What a player link did, returned by the task of [`connect_with_handle`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// The run id used in `hello`.
    pub run: String,
    /// The AAC's session id (from the last `welcome`).
    pub session: Option<String>,
    /// Highest event number received in that session.
    pub last_event: u64,
    /// Connections that reached `welcome`.
    pub connections: u32,
    /// Actions sent again after a reconnection.
    pub resent: u64,
    /// Events and perceptions dropped because already received.
    pub duplicates: u64,
    /// Error messages received from the AAC.
    pub errors: u64,
}

/// Why a player link stopped for good.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkError {
    /// The AAC refused the `hello` (`unauthorized`, `version`).
    Refused { code: String, message: String },
    /// Another player took over the session (`replaced`).
    Replaced,
    /// The player closed its action sender but these actions were never
    /// acknowledged within the linger time.
    Unacknowledged(Vec<u64>),
    /// The player closed its action sender before the link ever reached the
    /// AAC: these actions were never sent (no linger then: a vehicle that
    /// never saw the run has nothing to stop).
    NeverConnected(Vec<u64>),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Refused { code, message } => write!(f, "the AAC refused the connection ({code}): {message}"),
            LinkError::Replaced => write!(f, "another player took over this session"),
            LinkError::Unacknowledged(seqs) => write!(f, "actions never acknowledged: {seqs:?}"),
            LinkError::NeverConnected(seqs) if seqs.is_empty() => write!(f, "the AAC was never reached"),
            LinkError::NeverConnected(seqs) => write!(f, "the AAC was never reached: actions {seqs:?} were never sent"),
        }
    }
}

impl std::error::Error for LinkError {}

/// Connects a player to the AAC at `addr` (`host:port`); see
/// [`connect_with_handle`].
pub fn connect(addr: impl Into<String>, options: ConnectOptions) -> Link {
    connect_with_handle(addr, options).0
}

/// Connects a player to the AAC at `addr` (`host:port`, resolved at each
/// attempt) and returns the player's [`Link`] at once, with the background
/// task's handle.
///
/// The task keeps trying until it is connected; the player sees
/// [`Inbound::Connected`] after each successful handshake and
/// [`Inbound::Disconnected`] when an established connection is lost.
/// Actions sent meanwhile are kept and sent on reconnection, with every
/// action not yet acknowledged. The task ends when the player drops
/// [`Link::inbound`], when it drops [`Link::actions`] and every action has
/// been acknowledged (or `linger` has passed), or when the AAC refuses the
/// `hello` (then [`Link::inbound`] closes: `recv()` returns `None`).
pub fn connect_with_handle(
    addr: impl Into<String>,
    options: ConnectOptions,
) -> (Link, JoinHandle<Result<LinkStats, LinkError>>) {
    let (link, end) = pair();
    let run = options.run.clone().unwrap_or_else(new_id);
    let (session, received) = options.delivered.as_ref().map(Delivered::get).unwrap_or_default();
    // A player that tracks what it handled always says it (0: nothing, in
    // a session it may not know yet: the AAC sends again all it holds).
    let resumed = options.delivered.is_some();
    let resuming = session.is_some();
    let player = Player {
        addr: addr.into(),
        opts: options,
        actions: end.actions,
        actions_open: true,
        inbound: end.inbound,
        pending: BTreeMap::new(),
        session,
        received,
        resumed,
        resuming,
        attempts: 0,
        linger_deadline: None,
        stats: LinkStats { run, ..LinkStats::default() },
    };
    (link, tokio::spawn(player.run()))
}

struct Player {
    addr: String,
    opts: ConnectOptions,
    actions: mpsc::UnboundedReceiver<Action>,
    actions_open: bool,
    inbound: mpsc::UnboundedSender<Inbound>,
    /// Actions sent or to send, not yet acknowledged, by seq.
    pending: BTreeMap<u64, Action>,
    /// The AAC session id and the highest event number received in it
    /// (handed to the player).
    session: Option<String>,
    received: u64,
    /// Whether the event numbers are meaningful (a welcome was received,
    /// or resuming).
    resumed: bool,
    /// This link continues an interrupted run (the AAC may have executed
    /// its actions before).
    resuming: bool,
    /// Failed connection attempts since the last connection.
    attempts: u32,
    linger_deadline: Option<Instant>,
    stats: LinkStats,
}

enum End {
    /// The connection failed or was lost; `welcomed` if it had reached `welcome`.
    Lost {
        welcomed: bool,
        why: String,
    },
    Fatal(LinkError),
    /// Every action acknowledged and the player closed its sender.
    Done,
    /// The player dropped its receiver.
    PlayerGone,
    /// The linger time is over.
    Linger,
}

const WHO: &str = "aac-link";

impl Player {
    fn log(&self, need: LogLevel, msg: std::fmt::Arguments<'_>) {
        log(self.opts.log, need, WHO, msg);
    }

    /// Logs `msg` and tells the player ([`Inbound::Notice`]).
    fn notice(&self, msg: String) {
        self.log(LogLevel::Info, format_args!("{msg}"));
        let _ = self.inbound.send(Inbound::Notice { message: msg });
    }

    /// The link never reached the AAC (and does not continue a run it may know).
    fn never_connected(&self) -> bool {
        self.stats.connections == 0 && !self.resuming
    }

    fn finished(&self) -> bool {
        !self.actions_open && self.pending.is_empty()
    }

    /// The highest event number to confirm to the AAC: what the player
    /// handled ([`ConnectOptions::delivered`]), else what the link received.
    fn confirmed(&self) -> u64 {
        match &self.opts.delivered {
            Some(d) => d.in_session(self.session.as_deref()).min(self.received),
            None => self.received,
        }
    }

    fn stats(&mut self) -> LinkStats {
        let mut s = self.stats.clone();
        s.session = self.session.clone();
        s.last_event = self.received;
        s
    }

    /// Takes what the action channel gave.
    fn take_action(&mut self, a: Option<Action>) -> Option<Action> {
        match a {
            Some(a) => {
                self.pending.insert(a.seq, a.clone());
                Some(a)
            }
            None => {
                self.actions_open = false;
                // No linger for a vehicle that never saw the run.
                let linger = if self.never_connected() { Duration::ZERO } else { self.opts.linger };
                self.linger_deadline = Some(Instant::now() + linger);
                None
            }
        }
    }

    async fn run(mut self) -> Result<LinkStats, LinkError> {
        let mut backoff = self.opts.backoff_min;
        loop {
            if self.finished() {
                return Ok(self.stats());
            }
            if self.linger_deadline.is_some_and(|d| Instant::now() >= d) {
                return self.give_up();
            }
            let attempt = timeout(self.opts.timeout, TcpStream::connect(self.addr.as_str())).await;
            let end = match attempt {
                Ok(Ok(stream)) => self.session(stream).await,
                Ok(Err(e)) => End::Lost { welcomed: false, why: format!("cannot connect to {}: {e}", self.addr) },
                Err(_) => End::Lost { welcomed: false, why: format!("connecting to {} timed out", self.addr) },
            };
            match end {
                End::Done | End::PlayerGone => return Ok(self.stats()),
                End::Linger => return self.give_up(),
                End::Fatal(e) => {
                    self.notice(format!("{e}; giving up"));
                    return Err(e);
                }
                End::Lost { welcomed, why } => {
                    if welcomed {
                        backoff = self.opts.backoff_min;
                        self.attempts = 0;
                        self.notice(format!("disconnected: {why}"));
                        if self.inbound.send(Inbound::Disconnected).is_err() {
                            return Ok(self.stats());
                        }
                    } else {
                        self.attempts += 1;
                        let queued = self.pending.len();
                        self.notice(format!(
                            "{why}; retrying in {:.1} s (attempt {}{})",
                            backoff.as_secs_f64(),
                            self.attempts,
                            if queued == 0 { String::new() } else { format!(", {queued} actions queued") }
                        ));
                    }
                    if !self.pause(backoff).await {
                        return Ok(self.stats());
                    }
                    backoff = (backoff * 2).min(self.opts.backoff_max);
                }
            }
        }
    }

    fn give_up(&mut self) -> Result<LinkStats, LinkError> {
        let seqs: Vec<u64> = self.pending.keys().copied().collect();
        if self.never_connected() {
            let e = LinkError::NeverConnected(seqs);
            self.notice(format!("{e}"));
            return Err(e);
        }
        self.notice(format!("linger time over; actions never acknowledged: {seqs:?}"));
        Err(LinkError::Unacknowledged(seqs))
    }

    /// Takes every action the player has already produced.
    fn drain_actions(&mut self) {
        use tokio::sync::mpsc::error::TryRecvError;
        while self.actions_open {
            match self.actions.try_recv() {
                Ok(a) => {
                    self.take_action(Some(a));
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    self.take_action(None);
                }
            }
        }
    }

    /// Waits `d` while collecting actions; false when the player is gone.
    async fn pause(&mut self, d: Duration) -> bool {
        let deadline = Instant::now() + d;
        loop {
            let linger = self.linger_deadline;
            tokio::select! {
                _ = sleep_until(deadline) => return true,
                _ = self.inbound.closed() => return false,
                a = self.actions.recv(), if self.actions_open => { self.take_action(a); }
                _ = sleep_until(linger.unwrap_or(deadline)), if linger.is_some() => return true,
            }
            if self.finished() {
                return true;
            }
        }
    }

    async fn write(&self, wr: &mut OwnedWriteHalf, msg: &Message) -> io::Result<()> {
        let line = encode(msg);
        self.log(LogLevel::Messages, format_args!("-> {}", truncate(line.trim_end(), 300)));
        match timeout(self.opts.timeout, wr.write_all(line.as_bytes())).await {
            Ok(r) => r,
            Err(_) => Err(io::Error::new(io::ErrorKind::TimedOut, "write timed out")),
        }
    }

    async fn session(&mut self, stream: TcpStream) -> End {
        let _ = stream.set_nodelay(true);
        let peer = stream.peer_addr().map(|a| a.to_string()).unwrap_or_else(|_| self.addr.clone());
        let (rd, mut wr) = stream.into_split();
        let mut reader = LineReader::new(BufReader::new(rd), self.opts.max_line);
        let lost = |why: String| End::Lost { welcomed: false, why };

        // Handshake.
        let hello = Message::Hello(Hello {
            version: VERSION,
            token: self.opts.token.clone(),
            player: Some(self.opts.player.clone()),
            mission: Some(self.opts.mission.clone()),
            run: Some(self.stats.run.clone()),
            session: self.session.clone(),
            last_event: self.resumed.then(|| self.confirmed()),
        });
        if let Err(e) = self.write(&mut wr, &hello).await {
            return lost(format!("cannot send hello to {peer}: {e}"));
        }
        let deadline = Instant::now() + self.opts.timeout;
        let welcome = loop {
            let line = match timeout_at(deadline, reader.next_line()).await {
                Err(_) => return lost(format!("no welcome from {peer} within {:?}", self.opts.timeout)),
                Ok(Err(e)) => return lost(format!("reading from {peer}: {e}")),
                Ok(Ok(Line::Eof)) => return lost(format!("{peer} closed the connection before welcome")),
                Ok(Ok(Line::TooLong(n))) => {
                    let _ = self.reply_too_long(&mut wr, n).await;
                    continue;
                }
                Ok(Ok(Line::Text(t))) => t,
            };
            self.log(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(&line), 300)));
            match parse(&line) {
                Ok(Message::Welcome(w)) => break w,
                Ok(Message::Error(e)) => {
                    self.stats.errors += 1;
                    self.notice(format!("the AAC reports an error ({}): {}", e.code, truncate(&e.message, 200)));
                    return match ErrorCode::parse(&e.code) {
                        Some(ErrorCode::Unauthorized | ErrorCode::Version) => {
                            End::Fatal(LinkError::Refused { code: e.code, message: e.message })
                        }
                        Some(ErrorCode::Replaced) => End::Fatal(LinkError::Replaced),
                        _ => lost(format!("{peer} answered hello with an error ({}): {}", e.code, e.message)),
                    };
                }
                Ok(other) => {
                    let m = format!("expected `welcome`, got `{}`", other.type_name());
                    self.notice(format!("{peer}: {m}"));
                    let _ = self.write(&mut wr, &Message::error(ErrorCode::Unexpected, m, None)).await;
                }
                Err(pe) => {
                    self.notice(format!(
                        "{peer} sent a bad message ({pe}): {}",
                        truncate(&String::from_utf8_lossy(&line), 120)
                    ));
                    let _ = self.write(&mut wr, &pe.to_message()).await;
                }
            }
        };
        if welcome.version != VERSION {
            return End::Fatal(LinkError::Refused {
                code: ErrorCode::Version.as_str().into(),
                message: format!("the AAC welcomed us with version {}, we speak {VERSION}", welcome.version),
            });
        }
        let restarted = self.session.as_ref().is_some_and(|s| *s != welcome.session);
        if restarted {
            self.received = 0;
            if self.opts.reestablish {
                // Those the player produced before this welcome are dropped too.
                self.drain_actions();
                let dropped: Vec<u64> = std::mem::take(&mut self.pending).into_keys().collect();
                self.notice(format!(
                    "{peer} started a new session (it lost its state?): event numbers restart; actions {dropped:?} not sent again (the player re-establishes what runs)"
                ));
            } else {
                self.notice(format!("{peer} started a new session (it lost its state?): event numbers restart"));
            }
        }
        self.session = Some(welcome.session.clone());
        if self.inbound.send(Inbound::Session { id: welcome.session.clone(), restarted }).is_err() {
            return End::PlayerGone;
        }
        self.resumed = true;
        let confirmed: Vec<u64> = self.pending.range(..=welcome.last_seq).map(|(&s, _)| s).collect();
        for seq in confirmed {
            self.pending.remove(&seq);
            if self.inbound.send(Inbound::Ack { seq }).is_err() {
                return End::PlayerGone;
            }
        }
        self.stats.connections += 1;
        self.attempts = 0;
        self.notice(format!(
            "connected to {peer} (session {}, last seq {}, {} actions to send)",
            welcome.session,
            welcome.last_seq,
            self.pending.len()
        ));
        if self.inbound.send(Inbound::Connected).is_err() {
            return End::PlayerGone;
        }
        let lost = |why: String| End::Lost { welcomed: true, why };
        let resend: Vec<Action> = self.pending.values().cloned().collect();
        for a in resend {
            self.stats.resent += 1;
            if let Err(e) = self.write(&mut wr, &Message::Action(a.into())).await {
                return lost(format!("writing to {peer}: {e}"));
            }
        }

        // Session.
        let mut last_heard = Instant::now();
        let mut ping = tokio::time::interval_at(Instant::now() + self.opts.ping_interval, self.opts.ping_interval);
        ping.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            if self.finished() {
                let _ = wr.shutdown().await;
                self.log(LogLevel::Info, format_args!("every action acknowledged; closing"));
                return End::Done;
            }
            let linger = self.linger_deadline;
            let silence = last_heard + self.opts.timeout;
            tokio::select! {
                biased;
                _ = self.inbound.closed() => return End::PlayerGone,
                line = reader.next_line() => {
                    last_heard = Instant::now();
                    match line {
                        Err(e) => return lost(format!("reading from {peer}: {e}")),
                        Ok(Line::Eof) => return lost(format!("{peer} closed the connection")),
                        Ok(Line::TooLong(n)) => {
                            if let Err(e) = self.reply_too_long(&mut wr, n).await {
                                return lost(format!("writing to {peer}: {e}"));
                            }
                        }
                        Ok(Line::Text(t)) => {
                            if let Some(end) = self.on_line(&mut wr, &peer, &t).await {
                                return end;
                            }
                        }
                    }
                }
                a = self.actions.recv(), if self.actions_open => {
                    if let Some(a) = self.take_action(a) {
                        if let Err(e) = self.write(&mut wr, &Message::Action(a.into())).await {
                            return lost(format!("writing to {peer}: {e}"));
                        }
                    }
                }
                _ = ping.tick() => {
                    let p = Message::Ping(Ping { last_event: Some(self.confirmed()) });
                    if let Err(e) = self.write(&mut wr, &p).await {
                        return lost(format!("writing to {peer}: {e}"));
                    }
                }
                _ = sleep_until(silence) => {
                    let m = format!("no message for {:?}", self.opts.timeout);
                    let _ = self.write(&mut wr, &Message::error(ErrorCode::Timeout, m.clone(), None)).await;
                    return lost(format!("{peer}: {m}"));
                }
                _ = sleep_until(linger.unwrap_or(silence)), if linger.is_some() => return End::Linger,
            }
        }
    }

    async fn reply_too_long(&self, wr: &mut OwnedWriteHalf, n: usize) -> io::Result<()> {
        let m = format!("line of {n} bytes exceeds the limit of {} bytes; discarded", self.opts.max_line);
        self.notice(format!("the AAC sent a {m}"));
        self.write(wr, &Message::error(ErrorCode::TooLong, m, None)).await
    }

    /// Handles one line of an established session; `Some` ends it.
    async fn on_line(&mut self, wr: &mut OwnedWriteHalf, peer: &str, line: &[u8]) -> Option<End> {
        self.log(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(line), 300)));
        let reply = match parse(line) {
            Ok(Message::Ack { seq }) => {
                if self.pending.remove(&seq).is_some() && self.inbound.send(Inbound::Ack { seq }).is_err() {
                    return Some(End::PlayerGone);
                }
                None
            }
            Ok(m @ (Message::Event(_) | Message::Perception(_))) => {
                let n = match &m {
                    Message::Event(e) => e.n,
                    Message::Perception(p) => p.n,
                    _ => None,
                };
                if let Some(n) = n {
                    if n <= self.received {
                        self.stats.duplicates += 1;
                        self.notice(format!("dropped {} #{n}: already received", m.type_name()));
                        return None;
                    }
                    if n > self.received + 1 {
                        self.notice(format!(
                            "gap in the event numbers: events #{}..#{} never arrived (forgotten by the AAC?)",
                            self.received + 1,
                            n - 1
                        ));
                    }
                    self.received = n;
                }
                if let Some(ib) = m.to_inbound() {
                    if self.inbound.send(ib).is_err() {
                        return Some(End::PlayerGone);
                    }
                }
                None
            }
            Ok(Message::Pong {}) => None,
            Ok(Message::Ping(_)) => Some(Message::Pong {}),
            Ok(Message::Error(e)) => {
                self.stats.errors += 1;
                self.notice(format!(
                    "the AAC reports an error ({}{}): {}",
                    e.code,
                    e.seq.map(|s| format!(", seq {s}")).unwrap_or_default(),
                    truncate(&e.message, 200)
                ));
                return match ErrorCode::parse(&e.code) {
                    Some(ErrorCode::Unauthorized | ErrorCode::Version) => {
                        Some(End::Fatal(LinkError::Refused { code: e.code, message: e.message }))
                    }
                    Some(ErrorCode::Replaced) => Some(End::Fatal(LinkError::Replaced)),
                    Some(ErrorCode::Timeout) => Some(End::Lost { welcomed: true, why: e.message }),
                    _ => None,
                };
            }
            Ok(other) => {
                let m = format!("a player does not accept `{}`", other.type_name());
                self.notice(format!("the AAC sent an unexpected message: {m}"));
                Some(Message::error(ErrorCode::Unexpected, m, None))
            }
            Err(pe) => {
                self.notice(format!(
                    "the AAC sent a bad message ({pe}): {}",
                    truncate(&String::from_utf8_lossy(line), 120)
                ));
                Some(pe.to_message())
            }
        };
        if let Some(r) = reply {
            if let Err(e) = self.write(wr, &r).await {
                return Some(End::Lost { welcomed: true, why: format!("writing to {peer}: {e}") });
            }
        }
        None
    }
}

// ---------------------------------------------------------------------------
// AAC side
// ---------------------------------------------------------------------------

/// When the AAC acknowledges an action.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AckMode {
    /// As soon as it is handed to the session's handler.
    #[default]
    OnReceipt,
    /// When the handler sends [`Inbound::Ack`] through its [`AacEnd`] (it must
    /// do so in `seq` order): after it executed, or persisted, the action.
    ByHandler,
}

/// Options of [`serve`].
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// Shared secret: when set, a `hello` without it is refused.
    pub token: Option<String>,
    /// Silence after which a player is considered gone (it pings every
    /// second or so); also the time allowed for `hello` and for a write.
    pub timeout: Duration,
    /// When actions are acknowledged.
    pub ack: AckMode,
    /// Longest accepted line.
    pub max_line: usize,
    /// Sessions remembered (the least recently used idle ones are forgotten).
    pub max_sessions: usize,
    /// Events kept per session for a player that reconnects (the oldest are
    /// forgotten beyond that; a ping confirms and frees them).
    pub max_outbox: usize,
    /// Name sent in `welcome`.
    pub name: String,
    /// Logging on standard error.
    pub log: LogLevel,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            token: None,
            timeout: DEFAULT_TIMEOUT,
            ack: AckMode::OnReceipt,
            max_line: MAX_LINE,
            max_sessions: 64,
            max_outbox: 100_000,
            name: concat!("mcl-runtime/", env!("CARGO_PKG_VERSION")).into(),
            log: LogLevel::Off,
        }
    }
}

/// A session: one run of one mission, whatever connections carry it.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct SessionKey {
    /// Mission name from `hello` (empty when absent).
    pub mission: String,
    /// Run id from `hello` (empty when absent).
    pub run: String,
}

/// A new session handed to the handler of [`serve`].
pub struct Session {
    pub key: SessionKey,
    /// The session id sent in `welcome`.
    pub id: String,
    /// Player software from the `hello` that opened it.
    pub player: Option<String>,
    /// Actions (each `seq` once, in order) and the way back for events,
    /// perceptions and, with [`AckMode::ByHandler`], acknowledgements.
    pub end: AacEnd,
}

type Handler = Box<dyn FnMut(Session) + Send>;

/// An AAC server: sessions and their connections.
pub struct Server {
    inner: Arc<ServerInner>,
}

struct ServerInner {
    opts: ServeOptions,
    sessions: Mutex<HashMap<SessionKey, Arc<SessionState>>>,
    handler: Mutex<Option<Handler>>,
    next_conn: AtomicU64,
}

struct SessionState {
    id: String,
    actions: mpsc::UnboundedSender<Action>,
    inner: Mutex<SessionInner>,
}

struct SessionInner {
    /// Highest seq handed to the handler.
    last_forwarded: u64,
    /// Highest seq acknowledged (executed).
    last_acked: u64,
    /// Highest event number given.
    last_event: u64,
    /// Events not yet confirmed by the player: (number, encoded line).
    outbox: VecDeque<(u64, String)>,
    /// Duplicates of actions still being executed: each is acknowledged
    /// once its action is (protocol §5).
    owed: Vec<u64>,
    conn: Option<ConnHandle>,
    handler_gone: bool,
    touched: Instant,
}

struct ConnHandle {
    id: u64,
    tx: mpsc::UnboundedSender<String>,
    kill: Arc<Notify>,
}

impl SessionInner {
    fn send(&self, line: String) {
        if let Some(c) = &self.conn {
            let _ = c.tx.send(line);
        }
    }

    fn trim(&mut self, upto: u64) {
        while self.outbox.front().is_some_and(|(n, _)| *n <= upto) {
            self.outbox.pop_front();
        }
    }
}

/// Locks a mutex, ignoring poisoning (a panicking task must not take the
/// whole AAC down).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Accepts players on `listener` forever; `handler` receives each new session.
pub async fn serve<H>(listener: TcpListener, options: ServeOptions, handler: H)
where
    H: FnMut(Session) + Send + 'static,
{
    Server::new(options).run(listener, handler).await
}

impl Server {
    /// A server with no session yet.
    pub fn new(options: ServeOptions) -> Server {
        Server {
            inner: Arc::new(ServerInner {
                opts: options,
                sessions: Mutex::new(HashMap::new()),
                handler: Mutex::new(None),
                next_conn: AtomicU64::new(1),
            }),
        }
    }

    /// Declares a session known before this server started (restored from a
    /// state file): `id` is its session id, `last_seq` the highest seq it has
    /// executed. Returns its AAC end.
    pub fn restore(&self, key: SessionKey, id: String, last_seq: u64) -> AacEnd {
        let (state, end) = new_session(&self.inner, id, last_seq);
        lock(&self.inner.sessions).insert(key, state);
        end
    }

    /// Accepts players on `listener` forever; `handler` receives each new
    /// session (not the restored ones).
    pub async fn run<H>(self, listener: TcpListener, handler: H)
    where
        H: FnMut(Session) + Send + 'static,
    {
        *lock(&self.inner.handler) = Some(Box::new(handler));
        let who = "aac";
        if let Ok(a) = listener.local_addr() {
            log(self.inner.opts.log, LogLevel::Info, who, format_args!("listening on {a}"));
        }
        loop {
            match listener.accept().await {
                Ok((stream, peer)) => {
                    tokio::spawn(connection(self.inner.clone(), stream, peer));
                }
                Err(e) => {
                    // E.g. too many open files: wait and go on.
                    log(self.inner.opts.log, LogLevel::Info, who, format_args!("accept failed: {e}"));
                    sleep(Duration::from_millis(100)).await;
                }
            }
        }
    }
}

fn new_session(inner: &Arc<ServerInner>, id: String, last_seq: u64) -> (Arc<SessionState>, AacEnd) {
    let (link, end) = pair();
    let state = Arc::new(SessionState {
        id,
        actions: link.actions,
        inner: Mutex::new(SessionInner {
            last_forwarded: last_seq,
            last_acked: last_seq,
            last_event: 0,
            outbox: VecDeque::new(),
            owed: Vec::new(),
            conn: None,
            handler_gone: false,
            touched: Instant::now(),
        }),
    });
    tokio::spawn(pump(Arc::downgrade(&state), link.inbound, inner.opts.clone()));
    (state, end)
}

/// Carries what a session's handler sends to the session's connection.
async fn pump(session: Weak<SessionState>, mut rx: mpsc::UnboundedReceiver<Inbound>, opts: ServeOptions) {
    while let Some(item) = rx.recv().await {
        let Some(s) = session.upgrade() else { return };
        let mut g = lock(&s.inner);
        match item {
            Inbound::Event { event, activation, .. } => {
                g.last_event += 1;
                let n = g.last_event;
                let line = encode(&Message::Event(EventMsg { event, n: Some(n), activation }));
                g.send(line.clone());
                g.outbox.push_back((n, line));
            }
            Inbound::Perception { name, value, .. } => {
                g.last_event += 1;
                let n = g.last_event;
                let line = encode(&Message::Perception(PerceptionMsg { name, value, n: Some(n) }));
                g.send(line.clone());
                g.outbox.push_back((n, line));
            }
            Inbound::Ack { seq } => {
                if opts.ack == AckMode::ByHandler {
                    g.last_acked = g.last_acked.max(seq);
                    g.send(encode(&Message::Ack { seq }));
                    // Duplicates received while it was being executed.
                    let last = g.last_acked;
                    let owed: Vec<u64> = g.owed.iter().copied().filter(|&s| s <= last).collect();
                    g.owed.retain(|&s| s > last);
                    for s in owed {
                        g.send(encode(&Message::Ack { seq: s }));
                    }
                }
            }
            Inbound::Connected | Inbound::Disconnected | Inbound::Session { .. } | Inbound::Notice { .. } => {}
        }
        if g.outbox.len() > opts.max_outbox {
            let excess = g.outbox.len() - opts.max_outbox;
            g.outbox.drain(..excess);
        }
    }
    if let Some(s) = session.upgrade() {
        lock(&s.inner).handler_gone = true;
    }
}

/// Finds or creates the session of a `hello`; `true` if created.
fn session_for(inner: &Arc<ServerInner>, key: &SessionKey, player: Option<String>) -> (Arc<SessionState>, bool) {
    let mut sessions = lock(&inner.sessions);
    if let Some(s) = sessions.get(key) {
        return (s.clone(), false);
    }
    // Forget the least recently used idle sessions beyond the limit.
    while sessions.len() >= inner.opts.max_sessions.max(1) {
        let oldest = sessions
            .iter()
            .filter(|(_, s)| lock(&s.inner).conn.is_none())
            .min_by_key(|(_, s)| lock(&s.inner).touched)
            .map(|(k, _)| k.clone());
        match oldest {
            Some(k) => {
                sessions.remove(&k);
            }
            None => break,
        }
    }
    let (state, end) = new_session(inner, new_id(), 0);
    sessions.insert(key.clone(), state.clone());
    drop(sessions);
    let session = Session { key: key.clone(), id: state.id.clone(), player, end };
    match lock(&inner.handler).as_mut() {
        Some(h) => h(session),
        None => drop(session),
    }
    (state, true)
}

/// One player connection.
async fn connection(inner: Arc<ServerInner>, stream: TcpStream, peer: SocketAddr) {
    let opts = &inner.opts;
    let _ = stream.set_nodelay(true);
    let who = format!("aac {peer}");
    let lg = |need: LogLevel, msg: std::fmt::Arguments<'_>| log(opts.log, need, &who, msg);
    lg(LogLevel::Info, format_args!("connected"));
    let (rd, wr) = stream.into_split();
    let mut reader = LineReader::new(BufReader::new(rd), opts.max_line);
    let (tx, rx) = mpsc::unbounded_channel::<String>();
    let kill = Arc::new(Notify::new());
    let writer = tokio::spawn(write_loop(wr, rx, opts.timeout, opts.log, who.clone(), kill.clone()));
    let send = |m: &Message| {
        let _ = tx.send(encode(m));
    };
    let too_long = |n: usize| {
        let m = format!("line of {n} bytes exceeds the limit of {} bytes; discarded", opts.max_line);
        lg(LogLevel::Info, format_args!("{m}"));
        Message::error(ErrorCode::TooLong, m, None)
    };

    // Handshake.
    let deadline = Instant::now() + opts.timeout;
    let hello = loop {
        let line = match timeout_at(deadline, reader.next_line()).await {
            Err(_) => {
                send(&Message::error(ErrorCode::Timeout, "no hello", None));
                lg(LogLevel::Info, format_args!("no hello within {:?}; closing", opts.timeout));
                break None;
            }
            Ok(Err(_)) | Ok(Ok(Line::Eof)) => break None,
            Ok(Ok(Line::TooLong(n))) => {
                send(&too_long(n));
                continue;
            }
            Ok(Ok(Line::Text(t))) => t,
        };
        lg(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(&line), 300)));
        match parse(&line) {
            Ok(Message::Hello(h)) => break Some(h),
            Ok(Message::Error(e)) => lg(LogLevel::Info, format_args!("player reports ({}): {}", e.code, e.message)),
            Ok(other) => {
                let seq = if let Message::Action(a) = &other { Some(a.seq) } else { None };
                let m = format!("expected `hello` first, got `{}`", other.type_name());
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, seq));
            }
            Err(pe) => {
                lg(LogLevel::Info, format_args!("{pe}"));
                send(&pe.to_message());
            }
        }
    };
    let Some(hello) = hello else {
        drop(tx);
        let _ = writer.await;
        return;
    };
    if hello.version != VERSION {
        let m = format!("this AAC speaks protocol version {VERSION}, not {}", hello.version);
        lg(LogLevel::Info, format_args!("refused: {m}"));
        send(&Message::error(ErrorCode::Version, m, None));
        drop(tx);
        let _ = writer.await;
        return;
    }
    if let Some(expected) = &opts.token {
        if !token_matches(expected, hello.token.as_deref()) {
            let m = if hello.token.is_some() { "wrong token" } else { "this AAC requires a token" };
            lg(LogLevel::Info, format_args!("refused: {m}"));
            send(&Message::error(ErrorCode::Unauthorized, m, None));
            drop(tx);
            let _ = writer.await;
            return;
        }
    }
    let key =
        SessionKey { mission: hello.mission.clone().unwrap_or_default(), run: hello.run.clone().unwrap_or_default() };
    let (session, created) = session_for(&inner, &key, hello.player.clone());
    let conn_id = inner.next_conn.fetch_add(1, Ordering::Relaxed);
    {
        let mut g = lock(&session.inner);
        g.touched = Instant::now();
        if let Some(old) = g.conn.replace(ConnHandle { id: conn_id, tx: tx.clone(), kill: kill.clone() }) {
            let _ = old.tx.send(encode(&Message::error(
                ErrorCode::Replaced,
                "another connection took over this session",
                None,
            )));
            old.kill.notify_one();
        }
        let welcome = Welcome {
            version: VERSION,
            last_seq: g.last_acked,
            last_event: g.last_event,
            session: session.id.clone(),
            aac: Some(opts.name.clone()),
        };
        send(&Message::Welcome(welcome));
        // Re-send the events the player has not seen, if it tells which: all
        // of them if it names another session (it knew an older incarnation).
        if let Some(last) = hello.last_event {
            let from = match hello.session.as_deref() {
                Some(id) if id != session.id => 0,
                _ => last,
            };
            if from > 0 {
                g.trim(from);
            }
            for (_, line) in g.outbox.iter().filter(|(n, _)| *n > from) {
                let _ = tx.send(line.clone());
            }
        }
        lg(
            LogLevel::Info,
            format_args!(
                "{} session {} (mission `{}`, run `{}`, last seq {}, player {})",
                if created { "new" } else { "resumed" },
                session.id,
                key.mission,
                key.run,
                g.last_acked,
                hello.player.as_deref().unwrap_or("?")
            ),
        );
    }

    // Session.
    let mut last_heard = Instant::now();
    loop {
        let silence = last_heard + opts.timeout;
        let line = tokio::select! {
            _ = kill.notified() => {
                lg(LogLevel::Info, format_args!("closing (replaced by another connection, or the player stopped reading)"));
                break;
            }
            r = timeout_at(silence, reader.next_line()) => r,
        };
        last_heard = Instant::now();
        let line = match line {
            Err(_) => {
                let m = format!("no message for {:?}", opts.timeout);
                lg(LogLevel::Info, format_args!("{m}; closing"));
                send(&Message::error(ErrorCode::Timeout, m, None));
                break;
            }
            Ok(Err(_)) | Ok(Ok(Line::Eof)) => break,
            Ok(Ok(Line::TooLong(n))) => {
                send(&too_long(n));
                continue;
            }
            Ok(Ok(Line::Text(t))) => t,
        };
        lg(LogLevel::Messages, format_args!("<- {}", truncate(&String::from_utf8_lossy(&line), 300)));
        match parse(&line) {
            Ok(Message::Action(a)) => {
                if let Some(reply) = on_action(&session, opts, a, &lg) {
                    send(&reply);
                }
            }
            Ok(Message::Ping(p)) => {
                let mut g = lock(&session.inner);
                if let Some(n) = p.last_event {
                    g.trim(n);
                }
                g.touched = Instant::now();
                drop(g);
                send(&Message::Pong {});
            }
            Ok(Message::Pong {}) => {}
            Ok(Message::Error(e)) => {
                lg(LogLevel::Info, format_args!("player reports an error ({}): {}", e.code, truncate(&e.message, 200)))
            }
            Ok(Message::Hello(_)) => {
                let m = "already in a session: `hello` is only the first message";
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, None));
            }
            Ok(other) => {
                let m = format!("an AAC does not accept `{}`", other.type_name());
                lg(LogLevel::Info, format_args!("{m}"));
                send(&Message::error(ErrorCode::Unexpected, m, None));
            }
            Err(pe) => {
                lg(LogLevel::Info, format_args!("{pe}"));
                send(&pe.to_message());
            }
        }
    }
    {
        let mut g = lock(&session.inner);
        if g.conn.as_ref().is_some_and(|c| c.id == conn_id) {
            g.conn = None;
        }
        g.touched = Instant::now();
    }
    lg(LogLevel::Info, format_args!("disconnected"));
    drop(tx);
    let _ = writer.await;
}

/// An action of an established session; returns the immediate reply.
fn on_action(
    session: &SessionState,
    opts: &ServeOptions,
    a: ActionMsg,
    lg: &dyn Fn(LogLevel, std::fmt::Arguments<'_>),
) -> Option<Message> {
    let seq = a.seq;
    let mut g = lock(&session.inner);
    g.touched = Instant::now();
    if seq <= g.last_acked {
        lg(LogLevel::Info, format_args!("duplicate action seq {seq} (already executed): acknowledged, not executed"));
        return Some(Message::Ack { seq });
    }
    if seq <= g.last_forwarded {
        lg(
            LogLevel::Info,
            format_args!("duplicate action seq {seq} (being executed): not executed again, acknowledged once executed"),
        );
        g.owed.push(seq);
        return None;
    }
    if g.handler_gone || session.actions.send(a.into()).is_err() {
        g.handler_gone = true;
        let m = "this AAC cannot execute actions of this session any more";
        lg(LogLevel::Info, format_args!("seq {seq}: {m}"));
        return Some(Message::error(ErrorCode::Unavailable, m, Some(seq)));
    }
    g.last_forwarded = seq;
    if opts.ack == AckMode::OnReceipt {
        g.last_acked = seq;
        return Some(Message::Ack { seq });
    }
    None
}

async fn write_loop(
    mut wr: OwnedWriteHalf,
    mut rx: mpsc::UnboundedReceiver<String>,
    limit: Duration,
    level: LogLevel,
    who: String,
    kill: Arc<Notify>,
) {
    let mut batch = String::new();
    while let Some(line) = rx.recv().await {
        batch.clear();
        batch.push_str(&line);
        while let Ok(more) = rx.try_recv() {
            batch.push_str(&more);
            if batch.len() > 256 * 1024 {
                break;
            }
        }
        if level >= LogLevel::Messages {
            for l in batch.lines() {
                log(level, LogLevel::Messages, &who, format_args!("-> {}", truncate(l, 300)));
            }
        }
        match timeout(limit, wr.write_all(batch.as_bytes())).await {
            Ok(Ok(())) => {}
            _ => {
                log(level, LogLevel::Info, &who, format_args!("write failed or timed out; dropping the connection"));
                kill.notify_one();
                return;
            }
        }
    }
    let _ = wr.shutdown().await;
}

// ---------------------------------------------------------------------------
// A sans-IO vehicle behind the protocol
// ---------------------------------------------------------------------------

/// A vehicle as a sans-IO state machine with an agenda (the shape of
/// [`MockVehicle`](crate::mock::MockVehicle)): times are mission seconds
/// given by the caller; the vehicle schedules (and may cancel) the messages
/// it will send, and the caller takes them when they are due.
pub trait Vehicle: Send {
    /// Schedules what the vehicle sends by itself (called once, first).
    fn initial(&mut self);
    /// Executes an action at time `now`.
    fn on_action(&mut self, now: f64, action: &Action);
    /// Time of the next scheduled message.
    fn next_deadline(&self) -> Option<f64>;
    /// Removes and returns the first message due at or before `now`.
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)>;
    /// Warnings to log since the last call.
    fn take_warnings(&mut self) -> Vec<String> {
        Vec::new()
    }
}

impl Vehicle for crate::mock::MockVehicle {
    fn initial(&mut self) {
        crate::mock::MockVehicle::initial(self);
    }
    fn on_action(&mut self, now: f64, action: &Action) {
        crate::mock::MockVehicle::on_action(self, now, action);
    }
    fn next_deadline(&self) -> Option<f64> {
        crate::mock::MockVehicle::next_deadline(self)
    }
    fn pop_due(&mut self, now: f64) -> Option<(f64, Inbound)> {
        crate::mock::MockVehicle::pop_due(self, now)
    }
    fn take_warnings(&mut self) -> Vec<String> {
        crate::mock::MockVehicle::take_warnings(self)
    }
}

/// Options of [`serve_vehicle`].
#[derive(Clone, Debug)]
pub struct VehicleOptions {
    /// Mission seconds per real second (> 0).
    pub speed: f64,
    /// A JSON file where each session's executed actions are written before
    /// they are acknowledged, and read back at start.
    pub state: Option<PathBuf>,
    /// Sessions kept in the state file.
    pub max_saved: usize,
    /// Logging on standard error (`Info` logs every executed action).
    pub log: LogLevel,
}

impl Default for VehicleOptions {
    fn default() -> Self {
        VehicleOptions { speed: 1.0, state: None, max_saved: 16, log: LogLevel::Off }
    }
}

/// An action executed by a vehicle, as saved in a state file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Executed {
    /// Mission time of execution.
    pub t: f64,
    /// How many messages the vehicle had sent in the session before it
    /// executed the action (absent in older state files: then every
    /// message due at `t` was).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sent_before: Option<u64>,
    pub action: Action,
}

/// One session of a state file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedSession {
    pub mission: String,
    pub run: String,
    /// Session id (sent in `welcome`).
    pub session: String,
    /// Wall-clock time (seconds since 1970) of mission time 0.
    pub epoch_unix: f64,
    pub speed: f64,
    /// Every action executed, in order.
    pub executed: Vec<Executed>,
}

impl SavedSession {
    /// Highest seq executed.
    pub fn last_seq(&self) -> u64 {
        self.executed.iter().map(|e| e.action.seq).max().unwrap_or(0)
    }

    fn key(&self) -> SessionKey {
        SessionKey { mission: self.mission.clone(), run: self.run.clone() }
    }
}

/// The content of a `--state` file.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StateFile {
    pub version: u32,
    pub sessions: Vec<SavedSession>,
}

impl StateFile {
    /// Reads a state file; a missing file is an empty state.
    pub fn load(path: &std::path::Path) -> io::Result<StateFile> {
        use mcl_net::input::{read_source, Reason};
        match read_source(path) {
            Ok(text) => serde_json::from_str(&text).map_err(|e| {
                io::Error::new(io::ErrorKind::InvalidData, format!("{}: not a state file: {e}", path.display()))
            }),
            Err(e) if e.reason == Reason::NotFound => Ok(StateFile { version: 1, sessions: Vec::new() }),
            Err(e) => Err(io::Error::other(e.to_string())),
        }
    }

    /// Writes a state file atomically (a temporary file renamed over it).
    pub fn save(&self, path: &std::path::Path) -> io::Result<()> {
        let text = serde_json::to_string(self).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        std::fs::write(&tmp, text)?;
        std::fs::rename(&tmp, path)
    }
}

/// The state file shared by the sessions of one process.
#[derive(Clone)]
struct Store {
    path: PathBuf,
    max: usize,
    state: Arc<Mutex<StateFile>>,
}

impl Store {
    fn put(&self, s: &SavedSession) -> io::Result<()> {
        let mut g = lock(&self.state);
        match g.sessions.iter_mut().find(|x| x.mission == s.mission && x.run == s.run) {
            Some(x) => *x = s.clone(),
            None => g.sessions.push(s.clone()),
        }
        if g.sessions.len() > self.max {
            // Forget the oldest runs.
            g.sessions.sort_by(|a, b| a.epoch_unix.total_cmp(&b.epoch_unix));
            let excess = g.sessions.len() - self.max;
            g.sessions.drain(..excess);
        }
        g.save(&self.path)
    }
}

/// Serves a vehicle made by `make` for each new session (`None`: the session
/// gets `unavailable` errors), in real time at `vehicle.speed`. Actions are
/// acknowledged once the vehicle has executed them (and, with
/// `vehicle.state`, once they are saved); sessions saved in the state file
/// are restored first, their vehicle rebuilt by replaying the saved actions,
/// so a restarted process neither forgets nor repeats.
///
/// Returns only on a bad state file; otherwise serves forever.
pub async fn serve_vehicle<F>(
    listener: TcpListener,
    mut options: ServeOptions,
    vehicle: VehicleOptions,
    mut make: F,
) -> io::Result<()>
where
    F: FnMut(&SessionKey) -> Option<Box<dyn Vehicle>> + Send + 'static,
{
    options.ack = AckMode::ByHandler;
    let speed = if vehicle.speed.is_finite() && vehicle.speed > 0.0 { vehicle.speed } else { 1.0 };
    let store = match &vehicle.state {
        Some(path) => {
            let state = StateFile::load(path)?;
            Some(Store { path: path.clone(), max: vehicle.max_saved.max(1), state: Arc::new(Mutex::new(state)) })
        }
        None => None,
    };
    let server = Server::new(options);
    if let Some(store) = &store {
        let saved = lock(&store.state).sessions.clone();
        for s in saved {
            let key = s.key();
            let end = server.restore(key.clone(), s.session.clone(), s.last_seq());
            log(
                vehicle.log,
                LogLevel::Info,
                "vehicle",
                format_args!(
                    "restored session {} (mission `{}`, run `{}`, {} actions executed, last seq {})",
                    s.session,
                    s.mission,
                    s.run,
                    s.executed.len(),
                    s.last_seq()
                ),
            );
            match make(&key) {
                Some(v) => {
                    tokio::spawn(run_vehicle(v, end, s, store.clone().into(), vehicle.log));
                }
                None => log(vehicle.log, LogLevel::Info, "vehicle", format_args!("no vehicle for `{}`", key.mission)),
            }
        }
    }
    let level = vehicle.log;
    server
        .run(listener, move |session: Session| {
            let saved = SavedSession {
                mission: session.key.mission.clone(),
                run: session.key.run.clone(),
                session: session.id.clone(),
                epoch_unix: unix_now(),
                speed,
                executed: Vec::new(),
            };
            match make(&session.key) {
                Some(v) => {
                    tokio::spawn(run_vehicle(v, session.end, saved, store.clone(), level));
                }
                None => log(
                    level,
                    LogLevel::Info,
                    "vehicle",
                    format_args!("no vehicle for mission `{}`: its actions will be refused", session.key.mission),
                ),
            }
        })
        .await;
    Ok(())
}

/// Runs one session's vehicle in real time.
///
/// Inputs first, one message at a time: every action already received is
/// executed before the next due message is sent (a primitive disabled
/// before its answer is sent never answers), and the task yields after each
/// message.
///
/// Determinism across restarts: each executed action is saved with the
/// number of messages sent before it; replaying the saved actions after as
/// many messages (always the first of the agenda) rebuilds the same agenda
/// and sends the same messages in the same order (the transport numbers
/// them identically and the player drops the ones it has).
async fn run_vehicle(
    mut v: Box<dyn Vehicle>,
    mut end: AacEnd,
    mut saved: SavedSession,
    store: Option<Store>,
    level: LogLevel,
) {
    use tokio::sync::mpsc::error::TryRecvError;
    let who = format!("vehicle {}", saved.session);
    let clock = |s: &SavedSession| ((unix_now() - s.epoch_unix) * s.speed).max(0.0);
    // Messages sent in this session (by this process and, replayed, by the previous ones).
    let mut sent: u64 = 0;
    let send = |v: &mut Box<dyn Vehicle>, end: &AacEnd, sent: &mut u64, (t, item): (f64, Inbound)| -> bool {
        log(level, LogLevel::Messages, &who, format_args!("t={t:.3} sends {item:?}"));
        *sent += 1;
        for w in v.take_warnings() {
            log(level, LogLevel::Info, &who, format_args!("{w}"));
        }
        end.inbound.send(item).is_ok()
    };
    v.initial();
    // Replay what a previous process executed: same messages, same order.
    for ex in &saved.executed {
        match ex.sent_before {
            Some(k) => {
                while sent < k {
                    let Some(m) = v.pop_due(f64::INFINITY) else { break };
                    if !send(&mut v, &end, &mut sent, m) {
                        return;
                    }
                }
            }
            None => {
                while let Some(m) = v.pop_due(ex.t) {
                    if !send(&mut v, &end, &mut sent, m) {
                        return;
                    }
                }
            }
        }
        log(
            level,
            LogLevel::Info,
            &who,
            format_args!("restored seq={} t={:.3} {} (executed before restart)", ex.action.seq, ex.t, ex.action.action),
        );
        v.on_action(ex.t, &ex.action);
    }
    let _ = v.take_warnings();
    let execute = |v: &mut Box<dyn Vehicle>, saved: &mut SavedSession, sent: u64, a: Action| -> bool {
        let now = clock(saved).max(saved.executed.last().map_or(0.0, |e| e.t));
        v.on_action(now, &a);
        saved.executed.push(Executed { t: now, sent_before: Some(sent), action: a.clone() });
        if let Some(store) = &store {
            if let Err(e) = store.put(saved) {
                // Acknowledged anyway: the player must go on; only a
                // restart of this process could now repeat it.
                log(LogLevel::Info, LogLevel::Info, &who, format_args!("cannot save state: {e}"));
            }
        }
        log(
            level,
            LogLevel::Info,
            &who,
            format_args!("executed seq={} t={now:.3} {} ({} {})", a.seq, a.action, a.primitive, a.command),
        );
        for w in v.take_warnings() {
            log(level, LogLevel::Info, &who, format_args!("{w}"));
        }
        end.inbound.send(Inbound::Ack { seq: a.seq }).is_ok()
    };
    loop {
        loop {
            match end.actions.try_recv() {
                Ok(a) => {
                    if !execute(&mut v, &mut saved, sent, a) {
                        return;
                    }
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        let now = clock(&saved);
        if let Some(m) = v.pop_due(now) {
            if !send(&mut v, &end, &mut sent, m) {
                return;
            }
            tokio::task::yield_now().await;
            continue;
        }
        let wait = v.next_deadline().map(|d| Duration::from_secs_f64(((d - now) / saved.speed).clamp(0.0, 1e9)));
        tokio::select! {
            a = end.actions.recv() => {
                let Some(a) = a else { return };
                if !execute(&mut v, &mut saved, sent, a) {
                    return;
                }
            }
            _ = sleep(wait.unwrap_or(Duration::ZERO)), if wait.is_some() => {}
        }
    }
}
