//! The player side: [`connect`] returns a [`Link`] backed by a background
//! task that connects, shakes hands, forwards actions, keeps every action
//! until the AAC acknowledges it and re-sends it after a reconnection,
//! reconnects with capped exponential backoff, drops re-sent events (dedupe
//! by number), confirms what the player handled (the AAC's outbox) and
//! sends heartbeats.

use std::collections::BTreeMap;
use std::io;
use std::time::Duration;

use tokio::io::{AsyncWriteExt, BufReader};
use tokio::net::tcp::OwnedWriteHalf;
use tokio::net::TcpStream;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{sleep_until, timeout, timeout_at, Instant};

use crate::link::{pair, Action, Delivered, Inbound, Link};
use crate::protocol::{
    encode, parse, truncate, ErrorCode, Hello, Line, LineReader, Message, Ping, DEFAULT_PING_INTERVAL, DEFAULT_TIMEOUT,
    MAX_LINE, VERSION,
};

use super::*;

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
    /// The events that end the mission's tasks, announced in `hello`
    /// ([`crate::protocol::EventEnd::of_net`]).
    pub events: Vec<crate::protocol::EventEnd>,
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
            events: Vec::new(),
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
            events: self.opts.events.clone(),
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
